"""The documentation: the README short, its Quick start the two commands CI runs, its examples
and every tutorial's commands and snippets run as written, the reference generated from the
code complete (every deck key, command and option; every output column a run writes), and the
site built with warnings as errors where MkDocs is installed (the `docs` extra)."""

from __future__ import annotations

import importlib.util
import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import DECKS, ROOT, seed_deck, write_deck

DOCS = ROOT / "docs"
TUTORIALS = sorted((DOCS / "tutorials").glob("*.md"))
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```\s*$", re.MULTILINE | re.DOTALL)
#: the line CI runs (.ci/run)
CI_LINE = re.compile(r"^pip install .*\[test\].*pytest", re.MULTILINE)


def hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", DOCS / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def blocks(text: str) -> list[tuple[str, str]]:
    """The fenced code blocks of a Markdown text: (language, body), in order."""
    return [(m.group(1), m.group(2)) for m in FENCE.finditer(text)]


def section(text: str, title: str) -> str:
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else None]


def project_copy(tmp_path: Path) -> Path:
    """The decks (records, tutorial decks) in a folder of their own: commands write beside them."""
    shutil.copytree(DECKS, tmp_path / "decks", ignore=shutil.ignore_patterns("results", "motions"))
    return tmp_path


def run_line(line: str, cwd: Path) -> subprocess.CompletedProcess:
    """One command of a page as written; `rbhyst` is this interpreter's (python -m rbhyst)."""
    argv = shlex.split(line)
    if argv[0] == "rbhyst":
        argv = [sys.executable, "-m", "rbhyst", *argv[1:]]
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=600, check=False)


def run_python(code: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=600,
                          check=False)


# ---------------------------------------------------------------- README


def test_the_readme_is_short_and_its_quick_start_is_two_commands_ci_runs_the_second():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 300
    quick = section(text, "Quick start")
    (_, body), = [b for b in blocks(quick) if b[0] == "sh"]
    lines = [line for line in body.splitlines() if line.strip()]
    assert len(lines) == 2
    assert lines[0].startswith("python3 -m venv .venv && . .venv/bin/activate && pip install . ")
    assert next(line for line in text.splitlines() if CI_LINE.match(line)) == lines[1]  # grep -m1 finds it first
    assert lines[1] == 'pip install ".[test]" && pytest -q'


def test_the_readme_examples_run(tmp_path):
    """The ten-line deck (beside the sample decks' records) and the ten lines of Python."""
    root = project_copy(tmp_path)
    text = (ROOT / "README.md").read_text()
    deck, = [body for lang, body in blocks(section(text, "A deck in ten lines")) if lang == "toml"]
    (root / "decks" / "readme.toml").write_text(deck)
    out = run_line("rbhyst run decks/readme.toml --no-plots", root)
    assert out.returncode == 0, out.stderr
    assert "wrote decks/results/readme" in out.stderr
    code, = [body for lang, body in blocks(section(text, "Python in ten lines")) if lang == "python"]
    out = run_python(code, root)
    assert out.returncode == 0, out.stderr
    assert (root / "results" / "seed" / "time_history.csv").exists()


# ---------------------------------------------------------------- tutorials


@pytest.mark.slow
@pytest.mark.parametrize("page", TUTORIALS, ids=lambda p: p.stem)
def test_a_tutorial_runs_as_written(page, tmp_path):
    """Every command of its sh blocks in order, every Python block (its printout equal to the
    text block that follows it, where one does), every file it includes there to be read."""
    root = project_copy(tmp_path)
    text = page.read_text()
    for path in re.findall(r'--8<-- "([^"]+)"', text):
        assert (ROOT / path).is_file(), path
    found = blocks(text)
    ran = 0
    for k, (lang, body) in enumerate(found):
        if lang == "sh":
            for line in body.splitlines():
                if line.strip() and not line.lstrip().startswith("#"):
                    out = run_line(line, root)
                    assert out.returncode == 0, f"{line}\n{out.stderr}"
                    ran += 1
        elif lang == "python":
            out = run_python(body, root)
            assert out.returncode == 0, out.stderr
            ran += 1
            if k + 1 < len(found) and found[k + 1][0] == "text":
                assert out.stdout.strip() == found[k + 1][1].strip()
    assert ran


def test_a_tutorial_shows_its_deck_as_the_file_is():
    """The decks a tutorial shows are included from the files the commands run."""
    for page in TUTORIALS:
        for lang, body in blocks(page.read_text()):
            if lang == "toml":
                assert body.strip().startswith("--8<--"), page.name


# ---------------------------------------------------------------- reference


def test_every_deck_key_of_the_schema_is_in_the_reference():
    from rbhyst.model.schema import deck_schema

    schema = deck_schema()
    tables = {name: rows for name, _, _, rows in hooks().deck_key_tables()}
    wanted = {"(top level)": schema, **schema["$defs"]}
    assert set(tables) == set(wanted)
    for name, node in wanted.items():
        keys = [row[0] for row in tables[name]]
        assert keys == [f"`{k}`" for k in node["properties"]], name
    text = hooks().deck_keys_markdown()
    assert "| `kb` | number | N/m | required |" in text
    assert "| `dt` | number | s | required | > 0 |" in text
    assert '| `kinematics` | one of `"auto"`, `"small"`, `"exact"` |  | `"auto"` |' in text


def test_every_command_and_option_is_in_the_reference():
    h = hooks()
    text = h.cli_markdown()
    commands = h.cli_commands()
    assert {name for name, _ in commands} >= {"run", "modes", "qualify", "sweep", "schema", "report"}
    for name, cmd in commands:
        assert f"### rbhyst {name}\n" in text
        block = text.split(f"### rbhyst {name}\n", 1)[1].split("\n### ", 1)[0]
        for param in cmd.params:
            for opt in getattr(param, "opts", []):
                if opt.startswith("-"):
                    assert f"`{opt}" in block or f"/ {opt}" in block, (name, opt)


def normalised(column: str, points: tuple[str, ...]) -> str:
    """A column as the reference names its kind: e<k>_f_N, d<k>_v_m_s, <name>_at1_m_s2."""
    for name in points:
        if column.startswith(name + "_"):
            return "<name>" + column[len(name):]
    return re.sub(r"^([ed])\d+_", r"\1<k>_", column)


def test_every_column_and_file_a_run_writes_is_in_the_reference(tmp_path):
    """A plane run with support motion, a point, a damper, Rayleigh damping and spectra."""
    import rbhyst

    data = seed_deck(duration=0.3)
    data["dampers"] = [{"vertex": 1, "angle_deg": 0.0, "c": 500.0}]
    data["damping"] = {"rayleigh": {"ratio": 0.02, "modes": [1, 2]}}
    data["output"] = {"points": [{"name": "top", "point": [0.0, 1.0]}], "spectra": {"periods_s": [0.1, 0.5]}}
    folder = tmp_path / "out"
    rbhyst.run(write_deck(tmp_path, data), out=folder)
    reference = (DOCS / "reference" / "outputs.md").read_text()
    header = (folder / "time_history.csv").read_text().splitlines()[0].split(",")
    missing = [c for c in header if normalised(c, ("top",)) not in reference]
    assert missing == []
    spectra = (folder / "spectra.csv").read_text().splitlines()[0]
    assert f"`{spectra}`" in reference
    files = sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))
    assert [f for f in files if f.replace("_top", "_<name>") not in reference] == []


def test_every_column_of_a_body_in_space_is_in_the_reference(tmp_path):
    from test_isolators import isolator_cabinet

    import rbhyst

    data = isolator_cabinet()
    data["analysis"]["duration"] = 0.2
    data["output"] = {"points": [{"name": "top", "point": [0.0, 0.0, 2.0]}]}
    folder = tmp_path / "out"
    rbhyst.run(write_deck(tmp_path, data), out=folder)
    text = section((DOCS / "explanation" / "space.md").read_text(), "Columns")
    # "a1_m_s2..a3_m_s2": the range's every member
    def members(m):
        return ",".join(f"{m.group(1)}{i}{m.group(3)}" for i in range(int(m.group(2)), int(m.group(4)) + 1))

    text = re.sub(r"(\w*?)(\d)(_\w+)\.\.\w*?(\d)_\w+", members, text)
    text = text.replace("`<name>_u1_m,_u2_m,_u3_m,_at1_m_s2,_at2_m_s2,_at3_m_s2`",
                        ",".join(f"<name>_{c}" for c in ("u1_m", "u2_m", "u3_m", "at1_m_s2", "at2_m_s2", "at3_m_s2")))
    reference = text + (DOCS / "reference" / "outputs.md").read_text()
    header = (folder / "time_history.csv").read_text().splitlines()[0].split(",")
    assert [c for c in header if normalised(c, ("top",)) not in reference] == []


# ---------------------------------------------------------------- the site


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    """Skipped where the `docs` extra is not installed (CI installs the test extra only)."""
    for module in ("mkdocs", "material", "mkdocstrings"):
        pytest.importorskip(module)
    site = tmp_path / "site"
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    keys = (site / "reference" / "deck-keys" / "index.html").read_text()
    assert "acceleration_limit_g" in keys and "<!-- rbhyst:deck-keys -->" not in keys
    cli = (site / "reference" / "cli" / "index.html").read_text()
    assert "--tls-ca-file" in cli
    api = (site / "reference" / "api" / "index.html").read_text()
    assert "rbhyst.api.run" in api and "with_values" in api
    assert json.loads((site / "search" / "search_index.json").read_text())["docs"]
