"""rbhyst sweep: cases built and checked before anything runs, results equal to rbhyst run's,
statistics by their definition, resumable after Ctrl-C, SIGTERM or a killed worker, output
folders that hold other files, histories, and the same results on a Dask cluster.

Scenes are the seed's on its synthetic records (decks/records), cut short with
analysis.duration so that the whole file takes seconds of computing.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import tomli_w
import yaml

from rbhyst.model.deck import ACCEL_UNITS
from rbhyst.errors import InputError
from rbhyst.sweep import load_sweep, run_sweep
from rbhyst.analyses.sweep.store import FOLDER, JOURNAL
from conftest import DECKS, ROOT, invoke, records_or_skip, snapshot

G = ACCEL_UNITS["g"]


def read_cases(path: Path) -> list[dict[str, str]]:
    import csv

    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture
def project(tmp_path):
    """A user's folder: the seed deck and its records (copies), and notes of theirs."""
    folder = tmp_path / "study"
    shutil.copytree(DECKS / "records", folder / "records")
    shutil.copy(DECKS / "seed_wri.toml", folder / "seed_wri.toml")
    (folder / "notes.txt").write_text("mine\n")
    return folder


def write_sweep(folder: Path, data: dict, name: str = "sweep", fmt: str = "toml") -> Path:
    path = folder / f"{name}.{fmt}"
    path.write_text(tomli_w.dumps(data) if fmt == "toml" else yaml.safe_dump(data, sort_keys=False))
    return path


SYN = {"x1": {"file": "records/synthetic_x1.csv", "units": "g"},
       "x2": {"file": "records/synthetic_x2.csv", "units": "g"}}
SWAPPED = {"x1": {"file": "records/synthetic_x2.csv", "units": "g"},
           "x2": {"file": "records/synthetic_x1.csv", "units": "g"}}


def basic(duration: float = 2.0) -> dict:
    return {"deck": "seed_wri.toml",
            "motions": [{"name": "syn", **SYN}, {"name": "swapped", **SWAPPED}],
            "scale": {"factors": [0.5, 1.5]},
            "vary": {"body.mass": [700.0, 815.773], "analysis.duration": [duration]}}


# ---------------------------------------------------------------- results equal rbhyst run's


def test_every_case_equals_rbhyst_run_of_its_deck_exactly(project):
    sweep = write_sweep(project, basic())
    code, err = invoke("sweep", sweep, "--workers", "2")
    assert code == 0, err
    out = project / "results" / "sweep"
    rows = read_cases(out / "cases.csv")
    assert [r["case"] for r in rows] == [str(k) for k in range(1, 9)]
    assert list(rows[0])[:7] == ["case", "motion", "scale", "body.mass", "analysis.duration", "status", "message"]
    assert [(r["motion"], r["scale"], r["body.mass"]) for r in rows[:4]] == [
        ("syn", "0.5", "700.0"), ("syn", "0.5", "815.773"), ("syn", "1.5", "700.0"), ("syn", "1.5", "815.773")]
    motions = {"syn": SYN, "swapped": SWAPPED}
    for r in rows:
        assert r["status"] == "ok"
        data = _toml(project / "seed_wri.toml")
        data["body"]["mass"] = float(r["body.mass"])
        data["analysis"]["duration"] = 2.0
        data["excitation"]["support"] = {c: {**s, "scale": float(r["scale"])} for c, s in motions[r["motion"]].items()}
        path = project / "equivalent.toml"
        path.write_text(tomli_w.dumps(data))
        code, err = invoke("run", path, "--no-plots", "--out", project / "one")
        assert code == 0, err
        summary = json.loads((project / "one" / "summary.json").read_text())
        peaks = {k[len("peak_"):]: float(v) for k, v in r.items() if k.startswith("peak_")}
        assert peaks == summary["peaks"]  # every peak, exactly (cases.csv holds the shortest exact repr)
        assert r["message"] == "; ".join(summary["warnings"])  # a case's warnings are its message
        assert float(r["energy_balance_error"]) == summary["energy"]["balance_error"]
        assert float(r["energy_input_J"]) == summary["energy"]["input_J"]


def _toml(path: Path) -> dict:
    import tomllib

    return tomllib.loads(path.read_text())


def test_a_worker_gives_what_rbhyst_run_gives(project):
    import rbhyst
    from rbhyst.analyses.sweep.worker import flat_numbers, run_case, without_timings

    deck = rbhyst.load_deck(project / "seed_wri.toml")
    late = {"x1": {"type": "sine", "amplitude": 0.1, "frequency_hz": 2.0, "units": "g", "start": 3.0}}
    values = {"analysis.duration": 2.0, "excitation.support": late}  # a warning too
    summary = rbhyst.run(deck.with_values(values)).summary()
    assert summary["warnings"]
    for histories in (False, True):
        got = run_case(deck, "k", values, histories)
        assert got["status"] == "ok" and got["peaks"] == summary["peaks"]
        assert got["energy"] == {k: v for k, v in summary["energy"].items() if k != "warn_above"}
        assert got["message"] == "; ".join(summary["warnings"])
        assert got["accuracy"] == without_timings(flat_numbers(summary.get("accuracy") or {}))
        assert ("history" in got) == histories


def test_stats_by_their_definition(project):
    data = basic()
    data["motions"].append({"name": "sine", "x1": {"type": "sine", "amplitude": 0.2, "frequency_hz": 2.0,
                                                   "units": "g"}})
    sweep = write_sweep(project, data)
    assert invoke("sweep", sweep, "--workers", "2", "--no-plots")[0] == 0
    out = project / "results" / "sweep"
    rows = read_cases(out / "cases.csv")
    stats = read_cases(out / "stats.csv")
    assert list(stats[0]) == ["scale", "body.mass", "analysis.duration", "peak", "count", "failed",
                              "mean", "median", "p84", "max"]
    peaks = [k for k in rows[0] if k.startswith("peak_")]
    assert len(stats) == 4 * len(peaks)  # 2 levels x 2 masses, every peak
    for s in stats:
        x = sorted(float(r[s["peak"]]) for r in rows if r["scale"] == s["scale"] and r["body.mass"] == s["body.mass"])
        assert int(s["count"]) == len(x) == 3 and s["failed"] == "0"
        assert float(s["max"]) == x[2]
        assert float(s["median"]) == x[1]
        # 84th percentile, linear between order statistics: position 0.84 (n - 1) = 1.68
        assert float(s["p84"]) == pytest.approx(x[1] + 0.68 * (x[2] - x[1]), rel=1e-15, abs=0)
        assert float(s["mean"]) == pytest.approx((x[0] + x[1] + x[2]) / 3, rel=1e-15, abs=0)
    # the sine has no x2: its ag2 peak is 0, not missing
    assert {r["peak_ag2_m_s2"] for r in rows if r["motion"] == "sine"} == {"0.0"}


def test_stats_of_many_groups_are_each_groups_own(project):
    """stats.csv takes every (group, peak) with as many values at once: each row's numbers are
    the bits numpy gives for that group alone, whatever the group's size, its failed cases and
    the peaks its cases lack."""
    from rbhyst.analyses.sweep.cases import Case
    from rbhyst.analyses.sweep.tables import PERCENTILE, stats_table

    rng = np.random.default_rng(7)
    cases, results, number = [], {}, 0
    for g in range(60):
        for m in range(1 + g % 13):
            number += 1
            key = f"{number:032x}"
            cases.append(Case(number, f"m{m}", 1.0, 1.0, {"body.mass": 700.0 + g}, {}, key))
            if number % 11 == 0:
                results[key] = {"key": key, "status": "failed", "message": "diverged"}
                continue
            peaks = {"u1_m": float(rng.lognormal(-4, 2)), "at1_m_s2": float(np.round(rng.random() * 3))}
            if number % 7 == 0:
                peaks["at1_m_s2"] = None  # a peak the case does not have
            results[key] = {"key": key, "status": "ok", "peaks": peaks}
    header, rows = stats_table(cases, ["body.mass"], results)
    assert len(rows) == 60 * 2
    for row in rows:
        s = dict(zip(header, row))
        members = [c for c in cases if repr(c.vary["body.mass"]) == s["body.mass"]]
        x = np.array([results[c.key]["peaks"][s["peak"][5:]] for c in members if results[c.key]["status"] == "ok"
                      and results[c.key]["peaks"][s["peak"][5:]] is not None])
        assert s["count"] == str(len(x))
        assert s["failed"] == str(sum(results[c.key]["status"] == "failed" for c in members))
        want = ["", "", "", ""] if len(x) == 0 else [repr(float(f(x))) for f in (
            np.mean, np.median, lambda v: np.percentile(v, PERCENTILE), np.max)]
        assert [s["mean"], s["median"], s["p84"], s["max"]] == want


@pytest.mark.parametrize("values, repeated", [
    ([700, 700.0], "700.0"), ([True, 1, 1.0], "1.0"), ([0.0, -0.0], "-0.0"),
    ([float("nan"), 1.0, float("nan")], "nan"), (["a", "b", "a"], "'a'"), ([[1, 2], [2, 1], [1, 2]], "[1, 2]"),
    ([{"a": 1}, {"a": 1.0}], "{'a': 1.0}"), ([1, "1", True, [1], {"a": 1}, 2.5], None), (list(range(20_000)), None),
    ([*range(20_000), 19_999.0], "19999.0"),
])
def test_a_repeated_vary_value_is_found_as_same_value_finds_it(project, values, repeated):
    from rbhyst.analyses.sweep.spec import SweepSpec

    if repeated is None:
        SweepSpec.model_validate({"deck": "d.toml", "vary": {"body.mass": values}})
        return
    with pytest.raises(ValueError, match=re.escape(f"'body.mass': the value {repeated} is repeated")):
        SweepSpec.model_validate({"deck": "d.toml", "vary": {"body.mass": values}})


def test_pga_targets_scale_each_pair_to_its_larger_component(project):
    data = {"deck": "seed_wri.toml", "motions": [{"name": "syn", **SYN}, {"name": "swapped", **SWAPPED}],
            "scale": {"pga_g": [0.1, 0.3]}}
    sweep = write_sweep(project, data)
    assert invoke("sweep", sweep, "--workers", "2", "--no-plots")[0] == 0
    rows = read_cases(project / "results" / "sweep" / "cases.csv")
    assert [r["scale"] for r in rows] == ["0.1", "0.3", "0.1", "0.3"]
    for r in rows:  # the records' samples fall on the grid: the larger peak is the target
        peak = max(float(r["peak_ag1_m_s2"]), float(r["peak_ag2_m_s2"]))
        assert peak == pytest.approx(float(r["scale"]) * G, rel=1e-14)
        ratio = float(r["peak_ag2_m_s2"]) / float(r["peak_ag1_m_s2"])
        assert ratio == pytest.approx(0.25 / 0.35 if r["motion"] == "syn" else 0.35 / 0.25, rel=1e-6)


def test_el_centro_pair_from_a_folder_by_pattern(tmp_path):
    records = records_or_skip()
    data = {"deck": str(DECKS / "seed_wri.toml"),
            "motion_folders": [{"folder": str(records), "x1": "*270.AT2", "x2": "*180.AT2", "units": "g"}],
            "scale": {"pga_g": [0.4]}}  # the whole records: both peaks are in
    sw = load_sweep(write_sweep(tmp_path, data))
    assert sw.motions == ["I-ELC"]
    outcome = run_sweep(sw, out=tmp_path / "out", workers=1, plots=False)
    (row,) = read_cases(tmp_path / "out" / "cases.csv")
    assert row["status"] == "ok", row["message"]
    # the 180 component is the larger (0.3129 g against 0.2148 g): it is scaled to 0.4 g
    assert float(row["peak_ag2_m_s2"]) == pytest.approx(0.4 * G, rel=1e-12)
    assert float(row["peak_ag1_m_s2"]) / float(row["peak_ag2_m_s2"]) == pytest.approx(0.2148 / 0.3129, rel=2e-3)
    assert outcome.computed == 1


# ---------------------------------------------------------------- the sweep file and its mistakes


def test_motion_folders_pair_components_by_the_star(project):
    rec = project / "suite"
    rec.mkdir()
    for name in ("a", "b"):
        for c in ("x1", "x2"):
            shutil.copy(project / "records" / f"synthetic_{c}.csv", rec / f"{name}_{c}.csv")
    (rec / "readme.txt").write_text("not a record\n")
    data = {"deck": "seed_wri.toml", "motion_folders": [{"folder": "suite", "x1": "*_x1.csv", "x2": "*_x2.csv",
                                                         "units": "g"}],
            "vary": {"analysis.duration": [0.5]}}
    sw = load_sweep(write_sweep(project, data))
    assert sw.motions == ["a", "b"]
    assert sw.cases[0].values["excitation.support"] == {
        "x1": {"file": str((rec / "a_x1.csv").resolve()), "units": "g", "scale": 1.0},
        "x2": {"file": str((rec / "a_x2.csv").resolve()), "units": "g", "scale": 1.0}}
    # same contents, same key: a and b are one computation
    assert sw.cases[0].key == sw.cases[1].key
    (rec / "b_x2.csv").unlink()
    with pytest.raises(InputError) as err:
        load_sweep(write_sweep(project, data))
    assert err.value.problems == [f"motion_folders[1]: b_x1.csv matches x1 = '*_x1.csv' but b_x2.csv (x2) "
                                  f"is not in {project / 'suite'}"]


def test_listed_cases_and_yaml(project):
    data = {"deck": "seed_wri.toml", "motions": [{"name": "syn", **SYN}, {"name": "swapped", **SWAPPED}],
            "scale": {"factors": [1.0]},
            "cases": [{"values": {"body": {"mass": 700.0}, "analysis.duration": 0.5}},
                      {"motion": "swapped", "scale": 2.0, "values": {"analysis.duration": 0.5}}]}
    sw = load_sweep(write_sweep(project, data, fmt="yaml"))
    assert sw.vary_keys == ["body.mass", "analysis.duration"]
    assert [(c.motion, c.scale, c.vary) for c in sw.cases] == [
        ("syn", 1.0, {"body.mass": 700.0, "analysis.duration": 0.5}),
        ("swapped", 1.0, {"body.mass": 700.0, "analysis.duration": 0.5}),
        ("swapped", 2.0, {"analysis.duration": 0.5})]
    assert sw.cases[2].values["excitation.support"]["x1"]["scale"] == 2.0


@pytest.mark.parametrize("change, lines", [
    ({"motions": [{"name": "syn", **SYN, "x4": {}}]}, ["motions[1].x4: unknown key"]),
    ({"motions": [{"name": "syn", **SYN}, {"name": "syn", "x1": {"file": "records/synthetic_x1.csv",
                                                                  "units": "gee"}}]},
     ["motions[2].x1.units: must be 'g', 'm/s2' or 'cm/s2'"]),
    ({"motions": [{"name": "syn", **SYN}, {"name": "syn", **SWAPPED}]},
     ["motions[2]: the motion name 'syn' is taken by motions[1]"]),
    ({"motions": [{"name": "syn", "x1": {"file": "records/nope.csv", "units": "g"}}]},
     ["motions[1].x1.file: {folder}/records/nope.csv: no such file"]),
    ({"scale": {"factors": [1.0], "pga_g": [0.3]}}, ["scale: give exactly one of `factors` or `pga_g`"]),
    ({"vary": {"body.mass": [700.0, 700.0]}}, ["vary: 'body.mass': the value 700.0 is repeated"]),
    ({"colour": "red"}, ["colour: unknown key"]),
    ({"vary": {"hysteresis.wri_sheer.loading.kb": [2e5, 2.2e5]}},
     ["case 1 (motion syn, scale 1, hysteresis.wri_sheer.loading.kb = 200000.0): hysteresis.wri_sheer.loading.kb: "
      "no hysteresis.wri_sheer in the deck (every case)"]),
    ({"vary": {"body.masss": [700.0]}}, ["case 1 (motion syn, scale 1, body.masss = 700.0): body.masss: unknown key"]),
    ({"vary": {"body.mass": [700.0, -1.0, "heavy"]}},
     ["case 2 (motion syn, scale 1, body.mass = -1.0): body.mass: must be greater than 0",
      "case 3 (motion syn, scale 1, body.mass = heavy): body.mass: must be a valid number"]),
    ({"vary": {"analysis.dt": [0.001, 5.0]}, "motions": [{"name": "syn", **SYN}, {"name": "b", **SWAPPED}]},
     ["case 2 (motion syn, scale 1, analysis.dt = 5.0, analysis.duration = 2.0): analysis.dt: 5.0 s is larger than analysis.duration = "
      "2.0 s (and 1 more case)"]),
])
def test_mistakes_are_one_line_each_and_nothing_is_written(project, change, lines):
    data = {"deck": "seed_wri.toml", "motions": [{"name": "syn", **SYN}],
            "vary": {"analysis.duration": [2.0]}, **change}
    if "vary" in change and "analysis.duration" not in change["vary"]:
        data["vary"] = {**change["vary"], "analysis.duration": [2.0]} if "analysis.dt" in change["vary"] \
            else change["vary"]
    sweep = write_sweep(project, data)
    before = snapshot(project)
    code, err = invoke("sweep", sweep)
    assert code == 2
    assert err.splitlines() == [f"error: {x.format(folder=project)}" for x in lines]
    assert snapshot(project) == before and not (project / "results").exists()


def test_a_key_changes_with_what_the_result_depends_on(project):
    sw = load_sweep(write_sweep(project, basic()))
    keys = [c.key for c in sw.cases]
    assert len(set(keys)) == len(keys)
    again = load_sweep(write_sweep(project, {**basic(), "vary": {"analysis.duration": [2.0],
                                                                 "body.mass": [815.773, 700.0]}}, name="again"))
    assert {c.key for c in again.cases} == set(keys)  # order and key order do not matter
    moved = project.parent / "moved"
    shutil.copytree(project, moved)
    assert [c.key for c in load_sweep(moved / "sweep.toml").cases] == keys  # nor where the files are
    with open(moved / "records" / "synthetic_x2.csv", "a") as fh:
        fh.write("40.01,0.0\n")
    changed = [c.key for c in load_sweep(moved / "sweep.toml").cases]
    assert all(a != b for a, b in zip(keys, changed))  # every motion reads synthetic_x2
    deck = (moved / "seed_wri.toml").read_text().replace("title = ", "title = 'other' #")
    (moved / "seed_wri.toml").write_text(deck)
    assert [c.key for c in load_sweep(moved / "sweep.toml").cases] == changed  # the title changes no number


# ---------------------------------------------------------------- failures, resuming, interrupts


def test_failed_cases_are_recorded_and_do_not_stop_the_others(project):
    (project / "records" / "broken.csv").write_text("time_s,acc_g\n0.0,0.1\n0.01,oops\n")
    data = {"deck": "seed_wri.toml",
            "motions": [{"name": "syn", **SYN}, {"name": "broken", "x1": {"file": "records/broken.csv", "units": "g"}}],
            "vary": {"analysis.duration": [1.0], "analysis.dt": [0.001, 0.002], "analysis.max_substep_level": [0]}}
    sweep = write_sweep(project, data)
    code, err = invoke("sweep", sweep, "--workers", "2", "--no-plots")
    assert code == 0, err
    rows = read_cases(project / "results" / "sweep" / "cases.csv")
    assert [r["status"] for r in rows] == ["ok", "failed", "failed", "failed"]
    assert rows[1]["message"].startswith("t = ") and "1 substeps of dt = 0.002 s cannot resolve" in rows[1]["message"]
    assert rows[2]["message"] == f"excitation.support.x1: {project / 'records' / 'broken.csv'}:3: 'oops' is not a number"
    assert rows[1]["peak_u1_m"] == "" and float(rows[0]["peak_u1_m"]) > 0
    assert "1 ok, 3 failed" in err and "warning: case 2 (syn, scale 1.0) failed: t = " in err
    stats = read_cases(project / "results" / "sweep" / "stats.csv")
    assert {(s["analysis.dt"], s["count"], s["failed"]) for s in stats} == {("0.001", "1", "1"), ("0.002", "0", "2")}
    # a finished sweep is not computed again, failures included
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0 and "computed 0, 4 already in the folder" in err and "nothing to compute" in err


def test_resume_computes_only_what_is_missing_and_fresh_starts_over(project):
    sweep = write_sweep(project, basic(duration=1.0))
    sw = load_sweep(sweep)
    first = run_sweep(sw, workers=2, plots=False)
    assert (first.computed, first.reused) == (8, 0)
    before = (project / "results" / "sweep" / "cases.csv").read_bytes()
    assert run_sweep(load_sweep(sweep), workers=2, plots=False).computed == 0
    assert (project / "results" / "sweep" / "cases.csv").read_bytes() == before
    data = basic(duration=1.0)
    data["scale"]["factors"].append(1.0)  # one more level: only its cases run
    more = run_sweep(load_sweep(write_sweep(project, data)), workers=2, plots=False)
    assert (more.computed, more.reused) == (4, 8)
    fresh = run_sweep(load_sweep(write_sweep(project, data)), workers=2, plots=False, fresh=True)
    assert (fresh.computed, fresh.reused) == (12, 0)
    rows = read_cases(project / "results" / "sweep" / "cases.csv")
    old = {(r["motion"], r["scale"], r["body.mass"]): r for r in
           read_cases_from_bytes(before)}
    for r in rows:  # recomputed: the same bits
        if (r["motion"], r["scale"], r["body.mass"]) in old:
            o = old[(r["motion"], r["scale"], r["body.mass"])]
            assert {k: v for k, v in r.items() if k != "case"} == {k: v for k, v in o.items() if k != "case"}


def read_cases_from_bytes(data: bytes) -> list[dict[str, str]]:
    import csv
    import io

    return list(csv.DictReader(io.StringIO(data.decode())))


def journal_cases(out: Path) -> int:
    path = out / FOLDER / JOURNAL
    return max(0, len(path.read_bytes().splitlines()) - 1) if path.exists() else 0


def long_sweep(project: Path, n: int = 40) -> Path:
    """n cases of the seed's full 40 s: long enough to be interrupted."""
    return write_sweep(project, {"deck": "seed_wri.toml",
                                 "vary": {"body.mass": [800.0 + k for k in range(n)]}})


def start(sweep: Path, *args, session: bool = False) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "rbhyst", "sweep", sweep.name, "--workers", "2", "--no-plots",
                             *args], cwd=sweep.parent, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=session)


def wait_for(proc, out: Path, cases: int) -> None:
    deadline = time.monotonic() + 120
    while journal_cases(out) < cases:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.01)


def workers_of(proc) -> list:
    import psutil

    return [p for p in psutil.Process(proc.pid).children(recursive=True) if "python" in p.name().lower()]


def test_sigterm_keeps_what_finished_and_the_same_command_resumes(project):
    import psutil

    sweep = long_sweep(project)
    out = project / "results" / "sweep"
    proc = start(sweep)
    try:
        wait_for(proc, out, 3)
        workers = workers_of(proc)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert err.splitlines()[-1] == (f"interrupted: the finished cases are kept in {Path('results/sweep') / FOLDER}; "
                                    "the same command computes the rest")
    _, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive  # no worker outlives the sweep
    kept = journal_cases(out)
    assert 3 <= kept < 40
    assert not (out / "cases.csv").exists()
    proc = start(sweep)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert f"computed {40 - kept} on 2 local workers, {kept} already in the folder" in err
    rows = read_cases(out / "cases.csv")
    assert len(rows) == 40 and {r["status"] for r in rows} == {"ok"}


def test_ctrl_c_reaches_the_workers_too_and_only_the_sweep_answers(project):
    import psutil

    sweep = long_sweep(project)
    out = project / "results" / "sweep"
    proc = start(sweep, session=True)
    try:
        wait_for(proc, out, 3)
        workers = workers_of(proc)
        os.killpg(proc.pid, signal.SIGINT)  # as the terminal does: the whole process group
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    # a cold numba cache adds a compile note first; nothing else may be said (no worker's traceback)
    said = [line for line in err.splitlines() if not line.startswith("note: compiling")]
    assert said[1:] == [f"interrupted: the finished cases are kept in {Path('results/sweep') / FOLDER}; "
                        "the same command computes the rest"], err
    _, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive
    assert 3 <= journal_cases(out) < 40


def test_a_killed_worker_costs_only_its_batch(project):
    import rbhyst

    sweep = long_sweep(project)
    out = project / "results" / "sweep"
    proc = start(sweep)
    try:
        wait_for(proc, out, 2)
        workers_of(proc)[-1].kill()
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    rows = read_cases(out / "cases.csv")
    assert len(rows) == 40 and {r["status"] for r in rows} == {"ok"}
    sw = load_sweep(sweep)
    for k in (0, 20, 39):  # the same bits as a run that lost nothing
        peaks = rbhyst.run(sw.base.deck().with_values(sw.cases[k].values)).summary()["peaks"]
        assert {c[len("peak_"):]: float(v) for c, v in rows[k].items() if c.startswith("peak_")} == peaks


# ---------------------------------------------------------------- the output folder


def test_the_folder_may_hold_the_sweep_and_other_files(project):
    sweep = write_sweep(project, basic(duration=0.5))
    (project / "cases.csv").write_text("my own table\n")
    before = snapshot(project)
    code, err = invoke("sweep", sweep, "--out", project, "--workers", "1")
    assert code == 2
    assert err.splitlines() == [f"error: {project}: cases.csv exists and rbhyst did not write it (not listed in .rbhyst.json); "
                                "rbhyst will not overwrite it: move it away or choose another output folder"]
    assert snapshot(project) == before
    (project / "cases.csv").unlink()
    before = snapshot(project)
    os.chdir(project)
    try:
        code, err = invoke("sweep", sweep.name, "--out", ".", "--workers", "1")
        assert code == 0, err
        assert {k: v for k, v in snapshot(project).items() if k in before} == before
        ours = {"cases.csv", "stats.csv", "sweep.json", "ida.png", "vary.png", ".rbhyst.json", f"{FOLDER}/{JOURNAL}"}
        assert set(snapshot(project)) - set(before) == ours
        # a second sweep into the same folder: replaces its own files, keeps the user's
        code, err = invoke("sweep", sweep.name, "--out", ".", "--fresh", "--no-plots", "--workers", "1")
        assert code == 0, err
        assert set(snapshot(project)) - set(before) == ours - {"ida.png", "vary.png"}
        assert {k: v for k, v in snapshot(project).items() if k in before} == before
    finally:
        os.chdir(ROOT)


def test_a_foreign_journal_folder_is_refused(project):
    sweep = write_sweep(project, basic(duration=0.5))
    out = project / "out"
    (out / FOLDER).mkdir(parents=True)
    (out / FOLDER / "mine.txt").write_text("mine\n")
    before = snapshot(project)
    code, err = invoke("sweep", sweep, "--out", out)
    assert code == 2
    assert err.splitlines() == [f"error: {out}: {FOLDER} exists and rbhyst did not make it (no {JOURNAL} of "
                                "rbhyst's in it); move it away or choose another output folder"]
    assert snapshot(project) == before


# ---------------------------------------------------------------- histories and Dask


def test_histories_are_the_runs_rows(project):
    pq = pytest.importorskip("pyarrow.parquet")
    import rbhyst

    sweep = write_sweep(project, basic(duration=0.5))
    code, err = invoke("sweep", sweep, "--save-histories", "--no-plots", "--workers", "2")
    assert code == 0, err
    out = project / "results" / "sweep"
    table = pq.read_table(out / "histories.parquet")
    assert table.column_names[0] == "case" and table.num_rows == 8 * 501
    sw = load_sweep(sweep)
    for case in (sw.cases[0], sw.cases[5]):
        res = rbhyst.run(sw.base.deck().with_values(case.values))
        rows = table.filter(table.column("case").to_numpy() == case.number)
        got = np.column_stack([rows.column(c).to_numpy() for c in res.columns])
        assert rows.column_names[1:] == list(res.columns)
        assert np.array_equal(got, res.table)  # the same bits
    # a later run without --save-histories keeps them in the journal; one with it reuses them
    code, err = invoke("sweep", sweep, "--save-histories", "--no-plots")
    assert code == 0 and "computed 0, 8 already" in err


def test_dask_cluster_gives_the_local_results(project):
    distributed = pytest.importorskip("distributed")
    sweep = write_sweep(project, basic(duration=1.0))
    assert invoke("sweep", sweep, "--no-plots", "--workers", "2", "--out", project / "local")[0] == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        code, err = invoke("sweep", sweep, "--no-plots", "--scheduler", cluster.scheduler_address,
                           "--out", project / "dask")
    assert code == 0, err
    assert f"computed 8 on {cluster.scheduler_address} (2 worker threads)" in err
    assert (project / "dask" / "cases.csv").read_bytes() == (project / "local" / "cases.csv").read_bytes()
    assert (project / "dask" / "stats.csv").read_bytes() == (project / "local" / "stats.csv").read_bytes()


# ---------------------------------------------------------------- when things go wrong


def killer_sweep(project: Path, masses: list[float]) -> Path:
    return write_sweep(project, {"deck": "seed_wri.toml",
                                 "vary": {"body.mass": masses, "analysis.duration": [1.0]}})


def test_a_case_that_kills_its_worker_is_failed_and_the_others_finish(project, monkeypatch):
    import sweep_faults

    from rbhyst.analyses.sweep import backends

    monkeypatch.setattr(backends, "run_batch", sweep_faults.run_batch_or_die)
    masses = [700.0 + 10 * k for k in range(9)]
    masses.insert(4, sweep_faults.KILLER_MASS)
    sweep = killer_sweep(project, masses)
    t0 = time.perf_counter()
    code, err = invoke("sweep", sweep, "--workers", "2", "--no-plots")
    took = time.perf_counter() - t0
    assert code == 3, err
    assert err.splitlines()[-1] == ("error: the sweep is incomplete: case 5 killed its worker process every time "
                                    "(failed in cases.csv, not kept): the same command tries it again, with more "
                                    "memory per worker if that was the cause")
    out = project / "results" / "sweep"
    rows = read_cases(out / "cases.csv")
    message = "killed its worker process 3 times (SIGKILL: out of memory?)"
    assert [r["status"] for r in rows] == ["ok"] * 4 + ["failed"] + ["ok"] * 5
    assert rows[4]["message"] == message and rows[4]["peak_u1_m"] == ""
    assert "9 ok, 1 failed; computed 10 on 2 local workers" in err
    assert f"warning: case 5 (deck, scale 1.0) failed: {message}" in err
    assert journal_cases(out) == 9  # each case kept once; the killer is not kept
    # the same command tries only the killer again, which fails again within the bound
    code, err = invoke("sweep", sweep, "--workers", "2", "--no-plots")
    assert code == 3 and "computed 1 on 1 local worker, 9 already in the folder" in err, err
    assert read_cases(out / "cases.csv") == rows
    print(f"10 cases, one killing its worker: {took:.1f} s")


def test_a_batch_given_to_a_pool_whose_worker_just_died_is_lost_with_the_others(project):
    """The pool learns of a death in a thread of its own, between two waits of the sweep's
    loop: a batch submitted then used to raise BrokenProcessPool in the loop (the sweep ended
    with a traceback, exit 1, about one run in fifty of the test above). It is lost like the
    batches in flight, and recover() runs it again on a new pool."""
    from rbhyst.analyses.sweep.backends import LocalPool, WorkerLost

    sw = load_sweep(killer_sweep(project, [700.0, 710.0, 720.0]))
    cases = [(c.key, c.values) for c in sw.cases]
    pool = LocalPool(1, sw.base, False)
    try:
        first = pool.submit(cases[:1])
        assert pool.result(first)[0]["status"] == "ok"
        pid, = pool._pool._processes
        os.kill(pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while not pool._pool._broken and time.monotonic() < deadline:
            time.sleep(0.01)
        assert pool._pool._broken, "the pool did not see its worker die"
        late = pool.submit(cases[1:2])  # (raised here before)
        with pytest.raises(WorkerLost):
            pool.result(late)
        r = pool.recover(WorkerLost("a worker process died"), late, cases[1:2], {}, alone=False)
        assert r.again == cases[1:2] and not r.failed and not r.stop
        again = pool.submit(r.again)
        assert pool.result(again)[0]["status"] == "ok"
    finally:
        pool.close(kill=True)


def test_a_sweep_with_its_plots_ends_without_the_resource_tracker_s_warning(project):
    """The lock of the local pool's count of its workers is a semaphore of multiprocessing's: a
    sweep that drew its plots ended before it was collected, and the resource tracker printed
    "There appear to be 1 leaked semaphore objects" after every such sweep."""
    sweep = write_sweep(project, {"deck": "seed_wri.toml", "scale": {"factors": [0.5, 1.0]},
                                  "vary": {"analysis.duration": [1.0]}})
    done = subprocess.run([sys.executable, "-m", "rbhyst", "sweep", sweep.name, "--workers", "2"], cwd=project,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (project / "results" / "sweep" / "cases.csv").exists()
    assert "leaked" not in done.stderr and "Warning" not in done.stderr, done.stderr


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class DaskProcesses:
    """A scheduler and workers of our own on 127.0.0.1, in subprocesses (each in its own
    process group, logs in files), ended by ``stop``."""

    def __init__(self, folder: Path, env: dict | None = None):
        self.folder, self.env = folder, {**os.environ, **(env or {})}
        self.procs: list[subprocess.Popen] = []

    def _start(self, name: str, *args: str) -> subprocess.Popen:
        log = open(self.folder / f"{name}-{len(self.procs)}.log", "w")
        # (from its folder, outside the source tree: the workers import the installed package)
        p = subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=log, stderr=subprocess.STDOUT,
                             env=self.env, start_new_session=True, cwd=self.folder)
        log.close()
        self.procs.append(p)
        return p

    def scheduler(self, *tls: str, protocol: str = "tcp", port: int | None = None) -> tuple[subprocess.Popen, str]:
        import socket

        port = port or free_port()
        p = self._start("scheduler", "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard",
                        *(["--protocol", protocol] if protocol != "tcp" else []), *tls)
        deadline = time.monotonic() + 20
        while True:
            assert p.poll() is None and time.monotonic() < deadline, "the scheduler did not start"
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.05)
        return p, f"{protocol}://127.0.0.1:{port}"

    def workers(self, address: str, n: int = 2, *tls: str) -> subprocess.Popen:
        return self._start("workers", "worker", address, "--nworkers", str(n), "--nthreads", "1",
                           "--host", "127.0.0.1", "--no-dashboard", *tls)

    def wait_for_workers(self, address: str, n: int = 2, security=None) -> None:
        from distributed import Client

        with Client(address, timeout=20, security=security, set_as_default=False) as client:
            client.wait_for_workers(n, timeout=30)

    def kill(self, p: subprocess.Popen) -> None:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait(10)

    def stop(self) -> None:
        for p in self.procs:
            self.kill(p)


@pytest.fixture
def dask_processes(tmp_path):
    pytest.importorskip("distributed")
    # the tests' folder for the fault injection; rbhyst itself the installed package's (the source
    # tree has no kernels built)
    procs = DaskProcesses(tmp_path, env={"PYTHONPATH": str(Path(__file__).parent)})
    try:
        yield procs
    finally:
        procs.stop()


def sweep_on_dask(project: Path, dask_processes, n: int, connect: str):
    """A sweep of n cases of 20 s of the seed's record (a second a case) started on a scheduler
    and workers of its own, with Dask's connect timeout ``connect``."""
    sweep = write_sweep(project, {"deck": "seed_wri.toml",
                                  "vary": {"body.mass": [800.0 + k for k in range(n)], "analysis.duration": [20.0]}})
    scheduler, address = dask_processes.scheduler()
    dask_processes.workers(address)
    dask_processes.wait_for_workers(address)
    env = {**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": connect}
    proc = subprocess.Popen([sys.executable, "-m", "rbhyst", "sweep", sweep.name, "--no-plots", "--scheduler", address],
                            cwd=sweep.parent, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    return sweep, project / "results" / "sweep", scheduler, address, proc


@pytest.mark.slow
def test_a_lost_scheduler_stops_the_sweep_and_a_new_one_completes_it(project, dask_processes):
    n = 12
    sweep, out, scheduler, address, proc = sweep_on_dask(project, dask_processes, n, connect="2s")
    try:
        wait_for(proc, out, 3)
        dask_processes.kill(scheduler)
        t_lost = time.monotonic()
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - t_lost
    finally:
        proc.kill()
    kept = journal_cases(out)
    assert proc.returncode == 3, err
    assert 3 <= kept < n
    assert err.splitlines()[1:] == [
        f"error: {n - kept} case{'s' * (n - kept != 1)} could not be computed on {address} (2 worker threads): "
        f"lost the Dask scheduler (no connection for 2 s); the {kept} finished are kept in "
        f"{Path('results/sweep') / FOLDER}: the same command with a running scheduler (--scheduler) computes the rest"]
    assert not (out / "cases.csv").exists()
    print(f"scheduler lost -> sweep ended in {took:.1f} s")
    # a new scheduler: the same command completes the sweep, computing only what is missing
    scheduler, address = dask_processes.scheduler()
    dask_processes.workers(address)
    dask_processes.wait_for_workers(address)
    proc = subprocess.run([sys.executable, "-m", "rbhyst", "sweep", sweep.name, "--no-plots", "--scheduler", address],
                          cwd=sweep.parent, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"})
    assert proc.returncode == 0, proc.stderr
    assert f"computed {n - kept} on {address} (2 worker threads), {kept} already in the folder" in proc.stderr
    assert journal_cases(out) == n  # every case computed once in all
    code, err = invoke("sweep", sweep, "--no-plots", "--workers", "2", "--out", project / "local")
    assert code == 0, err
    assert (out / "cases.csv").read_bytes() == (project / "local" / "cases.csv").read_bytes()


@pytest.mark.slow
def test_on_dask_a_case_that_kills_its_workers_is_failed_and_the_others_finish(project, dask_processes,
                                                                               monkeypatch):
    import sweep_faults

    from rbhyst.analyses.sweep import backends

    monkeypatch.setattr(backends, "run_batch", sweep_faults.run_batch_or_die)
    dask_processes.env["DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES"] = "1"  # a task fails when 2 workers died
    _, address = dask_processes.scheduler()
    dask_processes.workers(address)
    dask_processes.wait_for_workers(address)
    masses = [700.0 + 10 * k for k in range(7)]
    masses.insert(2, sweep_faults.KILLER_MASS)
    sweep = killer_sweep(project, masses)
    t0 = time.perf_counter()
    code, err = invoke("sweep", sweep, "--no-plots", "--scheduler", address)
    took = time.perf_counter() - t0
    assert code == 3 and "error: the sweep is incomplete: case 3 killed its worker" in err, err
    out = project / "results" / "sweep"
    rows = read_cases(out / "cases.csv")
    assert [r["status"] for r in rows] == ["ok"] * 2 + ["failed"] + ["ok"] * 5
    assert rows[2]["message"] == "killed its worker 2 times (Dask KilledWorker: out of memory? see the workers' logs)"
    assert "7 ok, 1 failed; computed 8 on" in err
    assert journal_cases(out) == 7
    print(f"8 cases on Dask, one killing its workers: {took:.1f} s")


def make_certificates(folder: Path) -> dict[str, Path]:
    """A CA and one certificate it signs for 127.0.0.1 (scheduler, workers and client), by the
    openssl command."""
    openssl = shutil.which("openssl")
    if openssl is None:
        pytest.skip("no openssl command to make TLS certificates")
    folder.mkdir(parents=True, exist_ok=True)
    ext = folder / "leaf.ext"
    ext.write_text("basicConstraints = CA:FALSE\nkeyUsage = critical, digitalSignature, keyEncipherment\n"
                   "extendedKeyUsage = serverAuth, clientAuth\nsubjectAltName = IP:127.0.0.1, DNS:localhost\n"
                   "subjectKeyIdentifier = hash\nauthorityKeyIdentifier = keyid\n")

    def run(*args: str) -> None:
        subprocess.run([openssl, *args], cwd=folder, check=True, capture_output=True)

    run("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", "ca.key", "-out", "ca.pem", "-days", "2",
        "-subj", "/CN=rbhyst test CA", "-addext", "basicConstraints=critical,CA:TRUE",
        "-addext", "keyUsage=critical,keyCertSign,cRLSign")
    run("req", "-newkey", "rsa:2048", "-nodes", "-keyout", "node.key", "-out", "node.csr", "-subj", "/CN=127.0.0.1")
    run("x509", "-req", "-in", "node.csr", "-CA", "ca.pem", "-CAkey", "ca.key", "-CAcreateserial", "-out", "node.pem",
        "-days", "2", "-extfile", "leaf.ext")
    return {"ca": folder / "ca.pem", "cert": folder / "node.pem", "key": folder / "node.key"}


@pytest.mark.slow
def test_a_tls_scheduler_from_the_sweep_file_or_the_command_line(project, dask_processes, monkeypatch):
    from distributed.security import Security

    from rbhyst.analyses.sweep.backends import DaskCluster

    certs = make_certificates(project / "certs")
    stranger = make_certificates(project / "other")  # another CA's
    tls = ("--tls-ca-file", str(certs["ca"]), "--tls-cert", str(certs["cert"]), "--tls-key", str(certs["key"]))
    _, address = dask_processes.scheduler(*tls, protocol="tls")
    port = address.rsplit(":", 1)[1]
    dask_processes.workers(address, 2, *tls)
    dask_processes.wait_for_workers(address, security=Security(
        tls_ca_file=str(certs["ca"]), tls_client_cert=str(certs["cert"]), tls_client_key=str(certs["key"]),
        require_encryption=True))
    data = basic(duration=0.5)
    sweep = write_sweep(project, {**data, "cluster": {"scheduler": address, "tls_ca_file": "certs/ca.pem",
                                                      "tls_cert": "certs/node.pem", "tls_key": "certs/node.key"}})
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0, err
    assert f"computed 8 on {address} (2 worker threads)" in err
    # the same on the command line; and locally with --workers, whatever the file says
    plain = write_sweep(project, data, name="plain")
    code, err = invoke("sweep", plain, "--no-plots", "--scheduler", address, *tls, "--out", project / "cli")
    assert code == 0, err
    code, err = invoke("sweep", sweep, "--no-plots", "--workers", "2", "--out", project / "local")
    assert code == 0 and "computed 8 on 2 local workers" in err
    local = (project / "local" / "cases.csv").read_bytes()
    assert (project / "results" / "sweep" / "cases.csv").read_bytes() == local
    assert (project / "cli" / "cases.csv").read_bytes() == local
    # without the certificates, or not over TLS: refused, one line
    monkeypatch.setattr(DaskCluster, "LOST_AFTER_S", 3.0)
    for args, line in [
        (("--scheduler", address), f"--scheduler: {address}: needs its TLS files: --tls-ca-file, --tls-cert and "
                                   "--tls-key (or tls_ca_file, tls_cert and tls_key in the sweep file's [cluster])"),
        (("--scheduler", f"tcp://127.0.0.1:{port}"), f"--scheduler: cannot reach tcp://127.0.0.1:{port} ("),
        (("--scheduler", address, "--tls-ca-file", str(stranger["ca"]), "--tls-cert", str(stranger["cert"]),
          "--tls-key", str(stranger["key"])), f"--scheduler: cannot reach {address} ("),
    ]:
        t0 = time.perf_counter()
        code, err = invoke("sweep", plain, "--no-plots", *args, "--out", project / "refused")
        assert code == 2 and len(err.splitlines()) == 1 and err.startswith(f"error: {line}"), err
        print(f"{args[1]}: {err.strip()} ({time.perf_counter() - t0:.1f} s)")
    assert not (project / "refused").exists()  # nothing written


@pytest.mark.parametrize("cluster, args, lines", [
    (None, ("--tls-cert", "{folder}/seed_wri.toml"), ["--tls-cert: only with --scheduler (a Dask scheduler that wants TLS)"]),
    (None, ("--scheduler", "tcp://127.0.0.1:1", "--tls-ca-file", "{folder}/seed_wri.toml", "--tls-cert",
            "{folder}/nope.pem"),
     ["--tls-cert: {folder}/nope.pem: no such file",
      "--scheduler: tcp://127.0.0.1:1: with TLS certificates the address is tls://host:port"]),
    ({"scheduler": "tls://127.0.0.1:1", "tls_cert": "seed_wri.toml"}, (),
     ["cluster.tls_ca_file: missing: TLS needs the certificate of the CA that signed the scheduler's"]),
    ({"scheduler": "tls://127.0.0.1:1", "tls_ca_file": "certs/ca.pem", "tls_cert": "seed_wri.toml"},
     ("--tls-key", "{folder}/notes.txt"), ["cluster.tls_ca_file: {folder}/certs/ca.pem: no such file"]),
    ({"scheduler": "tls://127.0.0.1:1", "tls_certificate": "ca.pem"}, (), ["cluster.tls_certificate: unknown key"]),
    ({"scheduler": "tls://127.0.0.1:1"}, ("--workers", "2", "--tls-key", "{folder}/notes.txt"),
     ["--tls-key: only with --scheduler (a Dask scheduler that wants TLS)"]),
    ({"scheduler": ""}, (), ["cluster.scheduler: String should have at least 1 character"]),
])
def test_cluster_mistakes_are_one_line_each_and_nothing_is_written(project, cluster, args, lines):
    data = basic(duration=0.5)
    if cluster is not None:
        data["cluster"] = cluster
    sweep = write_sweep(project, data)
    before = snapshot(project)
    code, err = invoke("sweep", sweep, *[a.format(folder=project) for a in args])
    assert code == 2
    assert err.splitlines() == [f"error: {x.format(folder=project)}" for x in lines]
    assert snapshot(project) == before


def test_a_sweep_writes_only_into_its_output_folder(project):
    """Paths in a deck or a sweep file are read, never written to: a deck's output.directory
    (relative, absolute, its own folder), set in the deck or varied by the sweep, is left out
    of a sweep: everything goes into the sweep's output folder."""
    root = project.parent
    decks = root / "decks"
    decks.mkdir()
    data = _toml(project / "seed_wri.toml")
    data["output"] = {**data.get("output", {}), "directory": "."}
    for c in ("x1", "x2"):
        f = data["excitation"]["support"][c].get("file")
        if f:
            data["excitation"]["support"][c]["file"] = str(project / f)
    (decks / "deck.toml").write_text(tomli_w.dumps(data))
    sweep = write_sweep(project, {"deck": "../decks/deck.toml", "motions": [{"name": "syn", **SYN}],
                                  "vary": {"output.directory": ["../elsewhere", str(root / "absolute"), "/", "."],
                                           "analysis.duration": [0.5]}})
    before = snapshot(root)
    args = ("--save-histories",) if __import__("importlib").util.find_spec("pyarrow") else ()
    code, err = invoke("sweep", sweep, *args)
    assert code == 0, err
    after = snapshot(root)
    changed = {k for k in after if before.get(k) != after[k]} | (set(before) - set(after))
    assert changed and all(k.startswith("study/results/sweep/") for k in changed), changed
    assert not (root / "elsewhere").exists() and not (root / "absolute").exists()
    rows = read_cases(project / "results" / "sweep" / "cases.csv")
    assert [r["output.directory"] for r in rows] == ["../elsewhere", str(root / "absolute"), "/", "."]
    assert len({r["peak_u1_m"] for r in rows}) == 1  # one computation: output.directory is not in the key


@pytest.mark.slow
def test_a_second_sweep_into_the_same_folder_is_refused_and_kill_9_leaves_no_lock(project):
    import psutil

    sweep = long_sweep(project, 16)
    out = project / "results" / "sweep"
    proc = start(sweep)
    try:
        wait_for(proc, out, 2)
        code, err = invoke("sweep", sweep, "--workers", "1", "--no-plots")
        assert code == 2
        assert err.splitlines() == [f"error: {out}: another rbhyst sweep is writing into this folder"]
        workers = workers_of(proc)
        proc.kill()  # SIGKILL: no cleanup of its own
        proc.communicate(timeout=30)
    finally:
        proc.kill()
    _, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive  # its workers end with it
    kept = journal_cases(out)
    proc = start(sweep)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert f"computed {16 - kept} on 2 local workers, {kept} already in the folder" in err


@pytest.mark.slow
def test_a_scheduler_back_within_the_timeout_costs_only_the_batches_in_flight(project, dask_processes):
    n = 12
    sweep, out, scheduler, address, proc = sweep_on_dask(project, dask_processes, n, connect="20s")
    try:
        wait_for(proc, out, 3)
        dask_processes.kill(scheduler)
        kept = journal_cases(out)
        time.sleep(1.0)
        _, again = dask_processes.scheduler(port=int(address.rsplit(":", 1)[1]))
        assert again == address
        dask_processes.workers(address)
        _, err = proc.communicate(timeout=90)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert kept < n
    said = err.splitlines()
    assert len(said) == 3 and said[1].startswith(f"{n} ok, 0 failed; computed {n} on {address}"), err
    assert journal_cases(out) == n


def test_ending_the_workers_mid_message_does_not_hang_the_sweep():
    """A worker ended while it sent a result (Ctrl-C, a full disk that stops the sweep) leaves
    part of a message in the pool's result pipe; the pool's manager thread then waits for the
    rest, and closing the pool would wait for it forever (it did, once, under a full disk)."""
    import struct
    import threading

    from rbhyst.analyses.sweep.backends import LocalPool

    pool = LocalPool(1, None, False)
    assert pool._pool.submit(os.getpid).result(timeout=120) > 0  # a worker and the manager running
    # the start of a 1000-byte message, and no more
    os.write(pool._pool._result_queue._writer.fileno(), struct.pack("!i", 1000) + b"x" * 10)
    time.sleep(0.5)  # the manager is now reading it
    closing = threading.Thread(target=pool.close, kwargs={"kill": True}, daemon=True)
    closing.start()
    closing.join(30.0)
    assert not closing.is_alive(), "closing the pool hung on the half-sent result"


def test_stats_cells_that_need_quotes_read_back_as_written(tmp_path):
    """stats.csv is written as text, not through the csv module's rows: a vary value with a
    comma, a quote or a line break is quoted as the module quotes it, and reads back whole."""
    from rbhyst.analyses.sweep.cases import Case, format_value
    from rbhyst.analyses.sweep.tables import write_stats

    values = ["a,b", 'say "x"', "two\nlines", "plain"]
    cases = [Case(k + 1, "m", 1.0, 1.0, {"title": v}, {}, f"{k:032x}") for k, v in enumerate(values)]
    results = {c.key: {"key": c.key, "status": "ok", "peaks": {"u1_m": 0.5 + c.number}} for c in cases}
    write_stats(tmp_path / "stats.csv", cases, ["title"], results)
    with open(tmp_path / "stats.csv", encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["scale", "title", "peak", "count", "failed", "mean", "median", "p84", "max"]
    assert [r[1] for r in rows[1:]] == [format_value(v) for v in values]
    assert [r[5:] for r in rows[1:]] == [[repr(0.5 + k)] * 4 for k in range(1, 5)]


@pytest.mark.filterwarnings("ignore:invalid value encountered in subtract")  # (numpy's p84 of inf)
def test_a_group_of_one_case_repeats_its_cases_csv_cells_only_where_numpy_would(tmp_path):
    """stats.csv takes a group of one finished case's statistics from its cells in cases.csv
    (not formatted again) only where numpy's mean, median, p84 and max of the one value are
    that value: not for -0.0 (its mean is 0.0), inf (its p84 nan) or an int (cases.csv writes
    3, stats.csv 3.0). The same bytes as computing them all."""
    from rbhyst.analyses.sweep.cases import Case
    from rbhyst.analyses.sweep.tables import cases_table, peak_cells, write_stats

    cases = [Case(k + 1, "m", 1.0, 1.0, {"body.mass": 700.0 + k}, {}, f"{k:032x}") for k in range(12)]
    odd = [0.1, 3, -0.0, float("inf"), 0.0, float("nan"), 1e-300]
    results = {c.key: {"key": c.key, "status": "ok", "peaks": {"u1_m": odd[c.number % len(odd)],
                                                               "at1_m_s2": 1.0 / c.number}} for c in cases}
    results[cases[4].key] = {"key": cases[4].key, "status": "failed", "message": "diverged"}
    header, rows = cases_table(cases, ["body.mass"], results)
    write_stats(tmp_path / "computed.csv", cases, ["body.mass"], results)
    write_stats(tmp_path / "known.csv", cases, ["body.mass"], results, known=peak_cells(header, rows, cases))
    computed = (tmp_path / "computed.csv").read_bytes()
    assert (tmp_path / "known.csv").read_bytes() == computed
    assert b"peak_u1_m,1,0,0.0,0.0,-0.0,-0.0" in computed and b"peak_u1_m,1,0,inf,inf,nan,inf" in computed


def test_cases_csv_rows_held_as_lines_are_the_csv_module_s(tmp_path):
    """cases.csv's rows are held as their lines of text (tables.CaseRows) until the files are
    written: the file is the bytes of the csv module's rows, and every row, taken by index, by
    slice or in turn, reads back as the cells it was made from, a message with a comma, a quote
    or a line break among them."""
    from rbhyst.analyses.sweep.cases import Case, format_value
    from rbhyst.analyses.sweep.tables import CaseRows, cases_table, write_case_rows
    from rbhyst.files.csvfile import to_csv

    titles = ["a,b", 'say "x"', "two\nlines", "", " lead", "plain", "é"]
    cases = [Case(k + 1, f"m{k % 2}", 0.5 + k, 1.0, {"title": v}, {}, f"{k:032x}") for k, v in enumerate(titles)]
    results = {c.key: {"key": c.key, "status": "ok", "message": titles[-1 - k] if k % 3 else "",
                       "peaks": {"u1_m": 0.1 * c.number, "e1_f_N": -0.0}, "energy": {"E_in_J": 3}}
               for k, c in enumerate(cases)}
    results[cases[2].key] = {"key": cases[2].key, "status": "failed", "message": "diverged, at 1.2 s"}
    header, rows = cases_table(cases, ["title"], results)
    assert isinstance(rows, CaseRows) and len(rows) == len(cases)
    cells = [[c.number, c.motion, repr(c.scale), format_value(c.vary["title"]),
              results[c.key]["status"], results[c.key]["message"]] for c in cases]
    assert [r[:6] for r in rows] == cells
    assert [rows[i] for i in range(len(rows))] == list(rows) == rows[:]
    assert rows[2][6:] == [""] * (len(header) - 6) and rows[0][header.index("peak_e1_f_N")] == "-0.0"
    write_case_rows(tmp_path / "cases.csv", header, rows)
    assert (tmp_path / "cases.csv").read_bytes() == to_csv(header, list(rows)).encode("utf-8")
    with open(tmp_path / "cases.csv", encoding="utf-8", newline="") as fh:
        assert list(csv.reader(fh)) == [header, *[[str(r[0]), *r[1:]] for r in rows]]


def test_stats_numbers_are_each_value_s_own_repr():
    """stats.csv formats a group's mean, median, p84 and max once where they are equal, and
    never writes -0.0 as 0.0 (nor 0.0 as -0.0)."""
    from rbhyst.analyses.sweep.tables import _stats_text

    assert _stats_text(1.5, 1.5, 0.1 + 0.2, 0.1 + 0.2) == "1.5,1.5,0.30000000000000004,0.30000000000000004\n"
    assert _stats_text(-0.0, 0.0, 0.0, -0.0) == "-0.0,0.0,0.0,-0.0\n"
    assert _stats_text(float("nan"), float("nan"), 1.0, 1.0) == "nan,nan,1.0,1.0\n"


def test_a_case_runs_through_the_free_vibration_after_its_motion(tmp_path):
    """A sweep's case, as a qualification's run, goes on after its motion (a deck without
    analysis.duration): the peaks a record's end leaves for later are in its figures."""
    import tomllib

    import numpy as np
    import rbhyst
    from rbhyst.analyses.qualification.free_vibration import tail_s
    from rbhyst.analyses.sweep.worker import run_to_rest
    from conftest import write_deck

    t = np.arange(0.0, 1.02 + 1e-9, 0.001)
    pulse = np.where(t >= 1.0, 2.0 * np.sin(np.pi * (t - 1.0) / 0.02), 0.0)  # a 20 ms half-sine, last
    (tmp_path / "pulse.csv").write_text("time_s,acceleration_g\n" + "\n".join(f"{a:.6f},{b:.9e}" for a, b in
                                                                               zip(t, pulse)) + "\n")
    cab = tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())
    cab["excitation"] = {"support": {"x1": {"file": "pulse.csv", "units": "g"}}}
    cab["analysis"] = {"dt": 0.001, "integrator": "chang"}
    deck = rbhyst.load_deck(write_deck(tmp_path, cab))
    result, late = run_to_rest(deck, keep=False)
    f1 = result.summary()["modes"]["frequencies_hz"][0]
    assert result.steps * 0.001 == pytest.approx(1.02 + tail_s([f1]), abs=1.5e-3)
    alone = rbhyst.run(deck.with_values({"analysis.duration": 1.02 + tail_s([f1])})).summary()
    assert result.extremes.peaks()["u1_m"] == alone["peaks"]["u1_m"]
    short = rbhyst.run(deck.with_values({"analysis.duration": 1.02})).summary()
    assert short["peaks"]["u1_m"] < 0.9 * alone["peaks"]["u1_m"]
    assert all(line.startswith("the response may not have decayed ") for line in late)
