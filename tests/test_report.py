"""report.html: self-contained (every figure embedded and equal to its PNG, nothing fetched),
every number equal to the file it comes from, every warning and note, the deck as run; added
to a folder without touching the run's files; rendered by a real browser where one is installed."""

from __future__ import annotations

import base64
import hashlib
import json
import re
import shutil
import subprocess
import tomllib
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
import tomli_w

from rbhyst.report.html import fmt
from conftest import DECKS, invoke, snapshot


class Page(HTMLParser):
    """The images, the numbers with their sources, the text and every src/href of a page."""

    def __init__(self, text: str):
        super().__init__()
        self.images, self.numbers, self.links, self.pre, self.text = [], [], [], [], []
        self._number = None
        self._in_pre = False
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a)
        for k in ("src", "href"):
            if k in a:
                self.links.append(a[k])
        if "data-src" in a:
            self._number = [a, ""]
            self.numbers.append(self._number)
        if tag == "pre":
            self._in_pre = True
            self.pre.append("")

    def handle_endtag(self, tag):
        if tag == "pre":
            self._in_pre = False
        if tag in ("td", "span"):
            self._number = None

    def handle_data(self, data):
        self.text.append(data)
        if self._number is not None:
            self._number[1] += data
        if self._in_pre:
            self.pre[-1] += data


def resolve(folder: Path, src: str) -> float:
    """The number a data-src names: summary.json:peaks.u1_m, stats.csv:3:median (row from 0)."""
    import csv

    file, _, where = src.partition(":")
    if file.endswith(".json"):
        node = json.loads((folder / file).read_text())
        for part in where.split("."):
            node = node[int(part)] if isinstance(node, list) else node[part]
        return float(node)
    row, _, column = where.partition(":")
    with open(folder / file, newline="") as fh:
        return float(list(csv.DictReader(fh))[int(row)][column])


def check_page(folder: Path) -> Page:
    text = (folder / "report.html").read_text()
    page = Page(text)
    manifest = json.loads((folder / ".rbhyst.json").read_text())["files"]
    pngs = sorted(n for n in manifest if n.endswith(".png"))
    # every figure of the folder, embedded byte for byte
    assert sorted(i["data-file"] for i in page.images) == pngs
    for img in page.images:
        assert img["src"].startswith("data:image/png;base64,")
        data = base64.b64decode(img["src"].split(",", 1)[1], validate=True)
        assert data == (folder / img["data-file"]).read_bytes()
        import matplotlib.image

        assert matplotlib.image.imread(__import__("io").BytesIO(data)).size > 0  # it decodes
    # nothing from elsewhere
    assert all(link.startswith("data:") for link in page.links)
    bare = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", text)
    assert not re.search(r"(?i)(https?:|//[a-z0-9.-]+/|@import|url\(|<script|<link)", bare)
    # every number is its file's, shown as the page says
    assert len(page.numbers) > 20
    for attrs, shown in page.numbers:
        value = resolve(folder, attrs["data-src"])
        assert float(attrs["data-value"]) == value, attrs["data-src"]
        assert shown.strip() == fmt(value, attrs["data-kind"]), attrs["data-src"]
    return page


#: a deck's [report]: what the page to sign says it is about
FIELDS = {"project": "Substation 7 <upgrade>", "equipment": "Control cabinet CC-3", "engineer": "A. Engineer",
          "reviewer": "R. Reviewer", "notes": "Checked against the catalogue & the test data."}
STAMP = re.compile(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d UTC")


def about_section(folder: Path) -> str:
    """The report's "About these results", as its text."""
    text = (folder / "report.html").read_text()
    section = text[text.index('<section class="about">'):]
    return " ".join(Page(section[: section.index("</section>")]).text)


def assert_signed(folder: Path, files: dict[str, Path], command: str) -> None:
    """The page names each of ``files`` (key -> path) with the sha256 of its bytes, the command,
    the version, two moments, the deck's [report] fields; a signature block; page numbers in print."""
    from rbhyst import __version__

    text = about_section(folder)
    for key, path in files.items():
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert re.search(rf"{re.escape(key)} \S+ {path.stat().st_size} {digest}", text), (key, text)
    assert f"rbhyst {__version__}" in text and command in text
    assert len(STAMP.findall(text)) == 2  # results computed, report written
    for value in FIELDS.values():
        assert value in text
    page = (folder / "report.html").read_text()
    assert '<section class="signature">' in page and 'counter(page) " of " counter(pages)' in page
    signature = " ".join(Page(page[page.index('<section class="signature">'):]).text)
    assert "Prepared by A. Engineer" in signature and "Reviewed by R. Reviewer" in signature


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """The seed deck, 3 s, with points, strokes, a damper, Rayleigh damping and spectra, run with --report."""
    folder = tmp_path_factory.mktemp("report")
    shutil.copytree(DECKS / "records", folder / "records")
    d = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    d["analysis"]["duration"] = 3.0
    d["elements"][0]["stroke"] = 0.004
    d["elements"][1]["stroke"] = [-0.003, 0.004]
    d["dampers"] = [{"vertex": 6, "angle_deg": 0.0, "c": 500.0}]
    d["damping"] = {"rayleigh": {"ratio": 0.01, "modes": [1, 3]}}
    d["output"] = {"points": [{"name": "top", "point": [-0.1286, 1.0571]}], "spectra": {"damping": 0.05}}
    d["report"] = FIELDS
    deck = folder / "deck.toml"
    deck.write_text(tomli_w.dumps(d))
    code, err = invoke("run", deck, "--out", folder / "out", "--integrator", "central-difference", "--report")
    assert code == 0, err
    return folder / "out", err


def test_a_run_report_holds_everything_from_its_files(run_folder):
    out, err = run_folder
    page = check_page(out)
    summary = json.loads((out / "summary.json").read_text())
    text = " ".join(" ".join(page.text).split())
    for line in summary["warnings"] + summary["notes"]:
        assert " ".join(line.split()) in text
    assert summary["warnings"]  # (this scene warns: its alphat3)
    srcs = {a["data-src"] for a, _ in page.numbers}
    for k in range(1, 9):  # per element: force, deformation; per point: total accelerations
        assert {f"summary.json:peaks.e{k}_f_N", f"summary.json:peaks.e{k}_u_m"} <= srcs
    assert {"summary.json:elements.0.stroke.utilization", "summary.json:elements.1.stroke.utilization",
            "summary.json:peaks.top_at1_m_s2", "summary.json:peaks.top_at2_m_s2", "summary.json:rayleigh.a1_s",
            "summary.json:accuracy.estimated_error.alphat3", "summary.json:spectra.peaks.0.sa_m_s2"} <= srcs
    # the deck as run: the deck's own keys, with the command line's integrator
    deck = tomllib.loads(page.pre[0])
    assert deck == summary["deck"] and deck["analysis"]["integrator"] == "central-difference"
    assert "report.html" in json.loads((out / ".rbhyst.json").read_text())["files"]


def test_report_adds_its_file_and_touches_nothing_else(run_folder, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(run_folder[0], out)
    (out / "report.html").unlink()
    (out / "mine.txt").write_text("mine")
    before = snapshot(out)
    code, err = invoke("report", out)
    assert code == 0 and err.strip() == f"wrote {out / 'report.html'}"
    after = snapshot(out)
    assert {k: v for k, v in after.items() if k not in ("report.html", ".rbhyst.json")} == \
        {k: v for k, v in before.items() if k != ".rbhyst.json"}
    files = json.loads((out / ".rbhyst.json").read_text())["files"]
    assert set(files) == set(json.loads(before[".rbhyst.json"][0])["files"]) | {"report.html"}
    # the next run that writes no report takes the stale one away, like any file of its own
    code, err = invoke("run", run_folder[0].parent / "deck.toml", "--out", out, "--no-plots")
    assert code == 0, err
    assert not (out / "report.html").exists() and (out / "mine.txt").read_text() == "mine"


def test_report_refuses_what_is_not_a_results_folder_or_not_its_own(run_folder, tmp_path):
    code, err = invoke("report", tmp_path / "nowhere")
    assert code == 2 and err.splitlines() == [f"error: {tmp_path / 'nowhere'}: no such folder"]
    (tmp_path / "notes").mkdir()
    code, err = invoke("report", tmp_path / "notes")
    assert code == 2 and err.startswith(f"error: {tmp_path / 'notes'}: holds no results of rbhyst run, rbhyst sweep, rbhyst qualify or rbhyst shock")
    out = tmp_path / "out"
    shutil.copytree(run_folder[0], out)
    manifest = json.loads((out / ".rbhyst.json").read_text())
    manifest["files"].remove("report.html")
    (out / ".rbhyst.json").write_text(json.dumps(manifest))
    (out / "report.html").write_text("my own notes")
    before = snapshot(out)
    code, err = invoke("report", out)
    assert code == 2 and "report.html exists and rbhyst did not write it" in err and "Traceback" not in err
    code, err = invoke("run", run_folder[0].parent / "deck.toml", "--out", out, "--report", "--no-plots")
    assert code == 2 and "report.html exists and rbhyst did not write it" in err
    assert snapshot(out) == before


@pytest.fixture(scope="module")
def sweep_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep_report")
    shutil.copytree(DECKS / "records", folder / "records")
    d = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    d["analysis"].update(duration=2.0)
    (folder / "deck.toml").write_text(tomli_w.dumps(d))
    x1 = {"file": "records/synthetic_x1.csv", "units": "g"}
    x2 = {"file": "records/synthetic_x2.csv", "units": "g"}
    sweep = {"deck": "deck.toml", "motions": [{"name": "syn", "x1": x1, "x2": x2}, {"name": "swapped", "x1": x2, "x2": x1}],
             "scale": {"factors": [0.5, 1.5, 3.0]},
             "vary": {"body.mass": [700.0, 815.773]},
             "limit_states": [{"name": "at1", "quantity": "peak_at1_m_s2", "limit": 4.0},
                              {"name": "none", "quantity": "peak_u1_m", "limit": 1.0}],
             "fragility": {"bootstrap": 200}}
    (folder / "sweep.toml").write_text(tomli_w.dumps(sweep))
    code, err = invoke("sweep", folder / "sweep.toml", "--workers", "1", "--report")
    assert code == 0, err
    return folder / "results" / "sweep"


def test_a_sweep_report_holds_its_statistics_and_fragility(sweep_folder):
    page = check_page(sweep_folder)
    srcs = {a["data-src"].split(":")[0] for a, _ in page.numbers}
    assert {"sweep.json", "stats.csv", "fragility.csv", "cases.csv"} <= srcs
    assert any("accuracy_estimated_error_" in a["data-src"] for a, _ in page.numbers)  # the worst case's
    text = " ".join(page.text)
    assert "no case reaches the limit (0 of 6" in text  # a refused curve says why
    assert "fragility.png" in {i["data-file"] for i in page.images}


def test_a_run_report_says_when_by_which_rbhyst_and_command_and_from_which_files(run_folder):
    out, _ = run_folder
    folder = out.parent
    records = folder / "records"
    assert_signed(out, {"deck": folder / "deck.toml", "excitation.support.x1.file": records / "synthetic_x1.csv",
                        "excitation.support.x2.file": records / "synthetic_x2.csv"},
                  f"rbhyst run {folder / 'deck.toml'} --out {out} --integrator central-difference --report")


def test_a_report_without_provenance_says_its_files_cannot_be_checked(run_folder, tmp_path):
    folder = tmp_path / "o"
    shutil.copytree(run_folder[0], folder)
    s = json.loads((folder / "summary.json").read_text())
    del s["provenance"]  # as an older rbhyst wrote it
    (folder / "summary.json").write_text(json.dumps(s))
    assert invoke("report", folder)[0] == 0
    assert "summary.json says nothing of the files it was made from" in about_section(folder)


def test_an_unknown_report_field_is_one_line_naming_it(tmp_path):
    d = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    d["report"] = {"project": "p", "enginer": "A. Engineer"}
    deck = tmp_path / "deck.toml"
    deck.write_text(tomli_w.dumps(d))
    code, err = invoke("run", deck, "--out", tmp_path / "o")
    assert code == 2 and err.strip() == "error: report.enginer: unknown key"


@pytest.fixture(scope="module")
def qualification_folder(tmp_path_factory):
    """The sample cabinet qualified to AC156 on two motions, with --report."""
    folder = tmp_path_factory.mktemp("qualification_report")
    d = tomllib.loads((DECKS / "cabinet_qualify.toml").read_text())
    d["report"] = FIELDS
    deck = folder / "cabinet.toml"
    deck.write_text(tomli_w.dumps(d))
    code, err = invoke("qualify", deck, "--out", folder / "q", "--motions", "2", "--report")
    assert code == 0, err
    return folder / "q"


def test_a_qualification_report_is_signed_for_its_deck(qualification_folder):
    deck = qualification_folder.parent / "cabinet.toml"
    assert_signed(qualification_folder, {"deck": deck},
                  f"rbhyst qualify {deck} --out {qualification_folder} --motions 2 --report")


def test_a_qualification_on_the_deck_s_records_to_rrs_files_gives_each_file_s_sha256(tmp_path):
    """The deck's own motion and RRS files of its own: the deck, both records and both RRS
    files, each with its checksum (the verdict is beside the point: 2 s of record)."""
    shutil.copytree(DECKS / "records", tmp_path / "records")
    for axis, scale in (("x1", 1.0), ("x2", 0.5)):
        (tmp_path / f"rrs_{axis}.csv").write_text("frequency_hz,sa_g\n" + "".join(
            f"{f},{scale * a}\n" for f, a in ((1.0, 0.2), (2.0, 0.8), (10.0, 0.8), (33.0, 0.3))))
    d = tomllib.loads((DECKS / "cabinet_qualify.toml").read_text())
    d["analysis"]["duration"] = 2.0
    d["report"] = FIELDS
    d["qualify"] = {"rrs": "rrs_x1.csv", "rrs_x2": "rrs_x2.csv", "rrs_damping": 0.05, "motions": "deck",
                    "acceleration_limit_g": d["qualify"]["acceleration_limit_g"]}
    deck = tmp_path / "deck.toml"
    deck.write_text(tomli_w.dumps(d))
    out = tmp_path / "q"
    code, err = invoke("qualify", deck, "--out", out, "--report")
    assert code in (0, 1), err
    assert_signed(out, {"deck": deck, "qualify.rrs": tmp_path / "rrs_x1.csv", "qualify.rrs_x2": tmp_path / "rrs_x2.csv",
                        "excitation.support.x1.file": tmp_path / "records" / "synthetic_x1.csv",
                        "excitation.support.x2.file": tmp_path / "records" / "synthetic_x2.csv"},
                  f"rbhyst qualify {deck} --out {out} --report")


def test_a_qualification_report_holds_its_verdict_criteria_spectra_and_runs(qualification_folder):
    folder = qualification_folder
    q = json.loads((folder / "qualification.json").read_text())
    page = check_page(folder)
    srcs = {a["data-src"] for a, _ in page.numbers}
    assert {s.split(":")[0] for s in srcs} == {"qualification.json", "run_1/summary.json", "run_2/summary.json"}
    # every criterion: its demand, capacity, margin and each motion's demand
    for i, c in enumerate(q["criteria"]):
        for key in ("demand", "capacity", "margin", "per_motion.0", "per_motion.1"):
            assert f"qualification.json:criteria.{i}.{key}" in srcs
    # each motion's TRS against the RRS on every axis, and each run's accuracy
    for m in range(2):
        for axis in ("x1", "x2"):
            for key in ("min_ratio", "max_ratio", "peak_g", "peak_min_g"):
                assert f"qualification.json:motions.{m}.axes.{axis}.trs.{key}" in srcs
        assert f"qualification.json:accuracy.per_motion.{m}.estimated_error" in srcs
        assert f"run_{m + 1}/summary.json:peaks.top_at1_m_s2" in srcs  # the point the limits are set at
    text = " ".join(page.text)
    assert "The deck qualifies to ICC-ES AC156" in text and text.count("not met") == 0
    # the deck as run, read back as TOML, is qualification.json's
    assert len(page.pre) == 1 and tomllib.loads(page.pre[0]) == q["deck_as_run"]
    assert q["deck_as_run"]["qualify"]["standard"] == "ac156"
    assert "motion 2: x1 = motions/m2_x1.csv, x2 = motions/m2_x2.csv" in text


def test_a_failed_verdict_says_which_condition_failed(qualification_folder, tmp_path):
    folder = tmp_path / "q"
    shutil.copytree(qualification_folder, folder)
    q = json.loads((folder / "qualification.json").read_text())
    c = q["criteria"][5]
    c["capacity"] = c["demand"] / 2
    c["margin"], c["pass"], q["pass"] = 1 - c["demand"] / c["capacity"], False, False
    (folder / "qualification.json").write_text(json.dumps(q, indent=2) + "\n")
    code, err = invoke("report", folder)
    assert code == 0, err
    page = check_page(folder)
    text = " ".join(page.text)
    assert "The deck does not qualify to ICC-ES AC156" in text and "FAIL" in text
    assert "a pass needs every condition below, and 1 is not met" in text and text.count("not met") == 2
    assert "exceeded" in text
    assert f"{len(q['criteria']) - 1} of {len(q['criteria'])}" in text
    # the least margin at a glance is the failed criterion's
    glance = [a["data-src"] for a, _ in page.numbers if a["data-src"].endswith(".margin")][0]
    assert glance == "qualification.json:criteria.5.margin"


def test_a_qualification_to_rrs_files_names_them(qualification_folder, tmp_path):
    folder = tmp_path / "q"
    shutil.copytree(qualification_folder, folder)
    q = json.loads((folder / "qualification.json").read_text())
    q["standard"] = None
    for axis, r in q["rrs"].items():
        r["name"], r["source"] = f"rrs ({axis})", "cabinet_rrs.csv"
    (folder / "qualification.json").write_text(json.dumps(q, indent=2) + "\n")
    code, err = invoke("report", folder)
    assert code == 0, err
    text = " ".join(check_page(folder).text)
    assert "The deck qualifies to the required response spectra of cabinet_rrs.csv" in text
    assert "AC156" not in text.replace("qualified to AC156", "")  # (the deck's title says it)


def test_a_report_of_a_body_in_space_gives_its_points_vertical_accelerations(tmp_path):
    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = tomllib.loads((DECKS / "cabinet_3d.toml").read_text())
    d["analysis"]["duration"] = 0.5
    deck = tmp_path / "deck.toml"
    deck.write_text(tomli_w.dumps(d))
    code, err = invoke("run", deck, "--out", tmp_path / "out", "--no-plots", "--report")
    assert code == 0, err
    page = check_page(tmp_path / "out")
    srcs = {a["data-src"] for a, _ in page.numbers}
    for name in ("top1", "top2", "top3", "top4"):
        assert {f"summary.json:peaks.{name}_at{k}_m_s2" for k in "123"} <= srcs
        assert {f"summary.json:peaks.{name}_u{k}_m" for k in "123"} <= srcs
    assert "peak |at3| [m/s2]" in page.text


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.parametrize("which", ["run", "sweep", "qualification"])
def test_a_browser_renders_it(which, run_folder, sweep_folder, qualification_folder, tmp_path):
    browser = _chromium()
    if browser is None:
        pytest.skip("no chromium on this machine")
    import matplotlib.image

    folder = {"run": run_folder[0], "sweep": sweep_folder, "qualification": qualification_folder}[which]
    shot, pdf = tmp_path / "shot.png", tmp_path / "report.pdf"
    common = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              f"--user-data-dir={tmp_path / 'profile'}"]
    url = (folder / "report.html").resolve().as_uri()
    subprocess.run([*common, f"--screenshot={shot}", "--window-size=1200,2400", url], check=True, timeout=120,
                   capture_output=True)
    pixels = matplotlib.image.imread(shot)[:, :, :3]
    assert pixels.shape[:2] == (2400, 1200)
    assert pixels.std() > 0.1  # not blank: text, tables and figures
    assert (pixels.min(axis=2) < 0.5).mean() > 0.01  # dark ink on a good share of it
    subprocess.run([*common, "--no-pdf-header-footer", f"--print-to-pdf={pdf}", url], check=True, timeout=120,
                   capture_output=True)
    pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf.read_bytes()))
    assert pages >= 3


def test_a_standard_s_spectrum_is_printed_to_the_digits_it_carries(qualification_folder, tmp_path):
    """IEEE 693's plateau is 2.5 beta ZPA with beta(5 %) = (3.21 - 0.68 ln 5) / 2.1156 = 0.99999:
    its constants carry no five digits, so the page says 1.25 g and 1 g, not 1.2499 g nor 0.99999 g."""
    from rbhyst.analyses.qualification.rrs import ieee693

    folder = tmp_path / "q"
    shutil.copytree(qualification_folder, folder)
    q = json.loads((folder / "qualification.json").read_text())
    q["standard"] = "ieee693"
    q["rrs"] = {axis: r.describe() for axis, r in ieee693("moderate", None).items()}
    plateau = {axis: q["rrs"][axis]["breakpoints_sa_g"][1] for axis in ("x1", "x2")}  # at 1.1 Hz
    assert 0.99999 < plateau["x2"] < 1.0 and 1.24998 < plateau["x1"] < 1.25
    (folder / "qualification.json").write_text(json.dumps(q, indent=2) + "\n")
    assert invoke("report", folder)[0] == 0
    page = check_page(folder)
    shown = {a["data-src"]: v.strip() for a, v in page.numbers}
    assert shown["qualification.json:rrs.x1.breakpoints_sa_g.1"] == "1.25"
    assert shown["qualification.json:rrs.x2.breakpoints_sa_g.1"] == "1"
    assert not re.search(r"0\.9999|1\.2499", " ".join(page.text))
