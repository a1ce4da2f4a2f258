"""`rbhyst run` end to end: sample decks, formats, outputs, and bad decks that never hurt."""

from __future__ import annotations

import copy
import json
import subprocess
import sys

import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

from rbhyst.cli import app
from rbhyst.model.coordinates import SPACE
from rbhyst.solve.history import base_columns
from rbhyst.solve.result import BASE_COLUMNS, ENERGY_COLUMNS
from conftest import DECKS, seed_deck, write_deck

runner = CliRunner()


def run(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res.exit_code, res.stdout, res.stderr


def deck_files():
    return sorted(p for p in DECKS.iterdir() if p.suffix in (".toml", ".yaml", ".yml"))


@pytest.mark.parametrize("deck", deck_files(), ids=lambda p: p.name)
def test_every_sample_deck_runs(deck, tmp_path):
    with open(deck, "rb") if deck.suffix == ".toml" else open(deck) as fh:
        data = tomllib.load(fh) if deck.suffix == ".toml" else __import__("yaml").safe_load(fh)
    out = tmp_path / "out"
    if "body" in data:
        code, _, err = run("run", deck, "--out", out)
        assert code == 0, err
        names = (out / "time_history.csv").read_text().splitlines()[0].split(",")
        space = names[3] == "u3_m"  # a body in space (docs/explanation/space.md)
        base = base_columns(SPACE) if space else BASE_COLUMNS
        assert names[:len(base)] == list(base)
        assert names[-4:] == list(ENERGY_COLUMNS)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["analysis"]["steps"] > 0
        assert summary["energy"]["balance_error"] < 0.01
        modes = summary["modes"]  # the body's modes, as `rbhyst modes` gives them
        keys = [c.key("d") for c in SPACE] if space else ["u1", "u2", "theta3"]
        assert modes["coordinates"] == keys and len(modes["shapes"]) == len(keys)
        assert 0.0 < modes["frequencies_hz"][0] and np.all(np.diff(modes["frequencies_hz"]) >= 0.0)
        assert ("at_rest" in modes) == ("gravity" in data["body"])
        for png in ("model.png", "response_x1.png", "element_loops.png", "energy.png"):
            assert (out / png).stat().st_size > 10_000
    else:
        code, _, err = run("calibrate-plot", deck, "--out", out)
        assert code == 0, err
        assert (out / "loops.png").exists()


def test_seed_deck_outputs_match_the_contract(tmp_path):
    out = tmp_path / "seed"
    code, _, err = run("run", DECKS / "seed_wri.toml", "--out", out, "--no-plots")
    assert code == 0, err
    header = (out / "time_history.csv").read_text().splitlines()[0].split(",")
    expected = list(BASE_COLUMNS) + ["ag1_m_s2", "ag2_m_s2", "R1_N", "R2_N", "R3_Nm"]
    expected += [f"e{k}_{q}" for k in range(1, 9) for q in ("u_m", "f_N")]
    expected += list(ENERGY_COLUMNS)
    assert header == expected
    table = np.loadtxt(out / "time_history.csv", delimiter=",", skiprows=1)
    s = json.loads((out / "summary.json").read_text())
    assert s["body"]["area_m2"] == pytest.approx(1.68)
    assert s["body"]["inertia_kgm2"] == pytest.approx(297.7294, abs=1e-4)
    assert s["analysis"]["steps"] == 40000 and s["analysis"]["dt_s"] == 0.001
    assert table.shape == (40001, len(expected))
    np.testing.assert_allclose(table[:, 0], 0.001 * np.arange(40001), atol=1e-12)
    # the rows on the deck's dt, the compute step what the accuracy needs, and no warning
    chosen = s["analysis"]["chosen"]
    assert chosen["compute_step_s"] == pytest.approx(0.00025) and chosen["passes"][0]["compute_step_s"] == 0.001
    assert not s["warnings"] and max(s["accuracy"]["estimated_error"].values()) < 0.01
    # peaks are the motion's (every compute step): at least the rows' largest, and close to it;
    # total = relative + support acceleration
    rows = np.max(np.abs(table[:, 1]))
    assert rows <= s["peaks"]["u1_m"] <= rows * (1 + 1e-3)
    np.testing.assert_allclose(table[:, 10], table[:, 7] + table[:, 13], atol=1e-9)
    # elements counted twice report the same history
    np.testing.assert_array_equal(table[:, 18:20], table[:, 20:22])
    assert not list(out.glob("*.png"))


def test_toml_and_yaml_decks_agree_to_the_last_digit(tmp_path):
    data = seed_deck(duration=1.0)
    outs = []
    for fmt in ("toml", "yaml"):
        deck = write_deck(tmp_path, data, name=f"scene_{fmt}", fmt=fmt)
        out = tmp_path / f"out_{fmt}"
        code, _, err = run("run", deck, "--out", out, "--no-plots")
        assert code == 0, err
        outs.append((out / "time_history.csv").read_bytes())
    assert outs[0] == outs[1]


def test_yaml_reads_exponents_as_numbers(tmp_path):
    deck = tmp_path / "d.yaml"
    text = write_deck(tmp_path, seed_deck(), fmt="yaml").read_text().replace("dt: 0.001", "dt: 1e-3")
    deck.write_text(text)
    code, _, err = run("run", deck, "--out", tmp_path / "o", "--no-plots")
    assert code == 0, err


def test_command_line_overrides_the_deck(tmp_path):
    deck = write_deck(tmp_path, seed_deck(duration=0.5))
    code, _, err = run("run", deck, "--out", tmp_path / "o", "--no-plots", "--dt", "0.002",
                       "--integrator", "central-difference")
    assert code == 0, err
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert (s["analysis"]["dt_s"], s["analysis"]["integrator"], s["analysis"]["steps"]) == (
        0.002, "central-difference", 250)


def test_no_plots_never_imports_matplotlib(tmp_path):
    deck = write_deck(tmp_path, seed_deck(duration=0.2))
    code = (
        "import sys\nfrom rbhyst.cli import app\n"
        f"try:\n    app(['run', {str(deck)!r}, '--no-plots', '--out', {str(tmp_path / 'o')!r}])\n"
        "except SystemExit as e:\n    assert e.code in (0, None), e.code\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib was imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, cwd=tmp_path)


def test_importing_the_command_line_loads_no_heavy_library(tmp_path):
    """`rbhyst --help` and every command start from `import rbhyst.cli`: the libraries of the
    analysis, the plots, the sweeps and the deck's YAML come with the command that needs them."""
    heavy = ("numpy", "pydantic", "matplotlib", "scipy", "numba", "dask", "distributed", "pandas", "pyarrow",
             "rich", "yaml")
    code = f"import sys, rbhyst.cli; print([m for m in {heavy!r} if m in sys.modules])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert done.stdout.strip() == "[]", done.stdout + done.stderr


def test_a_toml_run_with_plots_loads_no_yaml_and_no_spectra_kernels(tmp_path):
    """A run without [output.spectra] draws its figures without the spectra's numba kernels,
    and a TOML deck is read without yaml (each costs a command a tenth of a second or more)."""
    deck = write_deck(tmp_path, seed_deck(duration=0.2))
    code = (
        "import sys\nfrom rbhyst.cli import app\n"
        f"try:\n    app(['run', {str(deck)!r}, '--out', {str(tmp_path / 'o')!r}])\n"
        "except SystemExit as e:\n    assert e.code in (0, None), e.code\n"
        "print(sorted(m for m in ('yaml', 'rbhyst.solve.spectra', 'numba') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    loaded = done.stdout.split("\n")[-2]
    # numba's own configuration imports yaml: where the kernels come from numba's JIT (a working
    # copy whose kernels changed since they were built), yaml comes with it, not with the deck
    want = "['numba', 'yaml']" if "numba" in loaded else "[]"
    assert loaded == want, done.stdout + done.stderr
    assert (tmp_path / "o" / "model.png").exists()


def test_default_output_folder_is_beside_the_deck(tmp_path):
    deck = write_deck(tmp_path, seed_deck(duration=0.1), name="scene")
    code, _, err = run("run", deck, "--no-plots")
    assert code == 0, err
    assert (tmp_path / "results" / "scene" / "summary.json").exists()


def test_a_record_finer_than_dt_is_followed_with_substeps(tmp_path):
    """A 0.1 ms shock pulse under dt = 1 ms is resolved, not aliased; output stays on dt."""
    t = np.arange(0, 0.2 + 1e-12, 1e-4)
    pulse = np.where((t > 0.0503) & (t < 0.0527), 30.0 * np.sin(np.pi * (t - 0.0503) / 0.0024), 0.0)
    np.savetxt(tmp_path / "pulse.csv", np.column_stack([t, pulse]), delimiter=",")
    data = seed_deck(duration=0.2)
    data["excitation"] = {"support": {"x1": {"file": "pulse.csv", "units": "m/s2"}}}
    outs = {}
    for dt in (1e-3, 1e-4):
        data["analysis"]["dt"] = dt
        deck = write_deck(tmp_path, data, name=f"d{dt}")
        code, _, err = run("run", deck, "--out", tmp_path / f"o{dt}", "--no-plots")
        assert code == 0, err
        outs[dt] = np.loadtxt(tmp_path / f"o{dt}" / "time_history.csv", delimiter=",", skiprows=1)
        if dt == 1e-3:
            assert "10 substeps per step" in err
    coarse, fine = outs[1e-3], outs[1e-4]
    assert coarse.shape[0] == 201
    # the coarse run saw the whole pulse: its velocity kick matches the fine run's
    np.testing.assert_allclose(coarse[:, 4], fine[::10, 4], atol=1e-3 * np.max(np.abs(fine[:, 4])))
    s = json.loads((tmp_path / "o0.001" / "summary.json").read_text())
    assert s["analysis"]["record_substeps"] == 10


# ------------------------------------------------------------------ bad decks


def _set(d, path, value):
    keys = path.split(".")
    for k in keys[:-1]:
        d = d[int(k)] if k.isdigit() else d[k]
    last = keys[-1]
    if value is DELETE:
        del d[int(last) if last.isdigit() else last]
    elif last.isdigit():
        d[int(last)] = value
    else:
        d[last] = value


DELETE = object()

BAD = [
    ("unknown key", "analysis.step", 0.1, "analysis.step: unknown key"),
    ("wrong type", "body.mass", "heavy", "body.mass:"),
    ("missing key", "elements.0.angle_deg", DELETE, "elements[1].angle_deg: required key is missing"),
    ("zero mass", "body.mass", 0.0, "body.mass: must be greater than 0"),
    ("negative dt", "analysis.dt", -0.001, "analysis.dt: must be greater than 0"),
    ("zero duration", "analysis.duration", 0.0, "analysis.duration: must be greater than 0"),
    ("dt over duration", "analysis.dt", 5.0, "analysis.dt: 5.0 s is larger than analysis.duration"),
    ("vertex out of range", "elements.2.vertex", 9, "elements[3].vertex: 9 is out of range"),
    ("undefined set", "elements.1.hysteresis", "nope", "elements[2].hysteresis: undefined set 'nope'"),
    ("alpha zero", "hysteresis.wri_axial.loading.alpha", 0.0, "hysteresis.wri_axial.loading.alpha:"),
    ("curves cross", "hysteresis.wri_shear.unloading.f0", -2000.0, "hysteresis.wri_shear: the limiting curves cross"),
    ("unknown units", "excitation.support.x1.units", "ft/s2", "excitation.support.x1.units:"),
    ("missing units", "excitation.support.x1.units", DELETE, "excitation.support.x1.units: required key is missing"),
    ("unknown integrator", "analysis.integrator", "rk4", "analysis.integrator: unknown integrator 'rk4'"),
    ("nan in deck", "body.mass", float("nan"), "body.mass:"),
    ("angle as string", "elements.0.angle_deg", "0", "elements[1].angle_deg:"),
    ("zero area", "body.vertices", [[0, 0], [1, 0], [2, 0]], "body.vertices: the polygon has zero area"),
    ("repeated vertex", "body.vertices", [[0, 0], [1, 0], [1, 1], [1, 0]], "body.vertices: vertices 2 and 4 coincide"),
    ("self-intersection", "body.vertices", [[0, 0], [1, 1], [1, 0], [0, 1]], "self-intersecting"),
    ("vertex and point", "elements.0.point", [0.0, 0.0], "elements[1]: give exactly one of"),
    ("free body", "elements", [{"vertex": 1, "angle_deg": 0.0, "hysteresis": "wri_axial"}],
     "elements: the body is not restrained"),
]


def _check_clean_failure(code, out_dir, stderr, expected, n_lines=None):
    assert code == 2, stderr
    lines = stderr.strip().splitlines()
    assert lines and all(line.startswith("error: ") for line in lines), stderr
    assert "Traceback" not in stderr
    assert any(expected in line for line in lines), stderr
    if n_lines is not None:
        assert len(lines) == n_lines, stderr
    assert not out_dir.exists()
    assert not list(out_dir.parent.glob(f".{out_dir.name}*"))


@pytest.mark.parametrize("name, path, value, expected", BAD, ids=[b[0] for b in BAD])
def test_bad_deck_gives_one_line_exit_2_and_writes_nothing(tmp_path, name, path, value, expected):
    data = copy.deepcopy(seed_deck())
    _set(data, path, value)
    deck = write_deck(tmp_path, data, fmt="yaml" if name == "nan in deck" else "toml")
    out = tmp_path / "out"
    code, _, err = run("run", deck, "--out", out)
    _check_clean_failure(code, out, err, expected, n_lines=1)


def test_every_problem_gets_its_own_line(tmp_path):
    data = copy.deepcopy(seed_deck())
    data["body"]["mass"] = -1.0
    data["analysis"]["dt"] = 0.0
    data["elements"][0]["angle_deg"] = "x"
    out = tmp_path / "out"
    code, _, err = run("run", write_deck(tmp_path, data), "--out", out)
    _check_clean_failure(code, out, err, "body.mass", n_lines=3)


@pytest.mark.parametrize("name, text, expected", [
    ("toml syntax", "[body\nmass = 1\n", "TOML syntax error"),
    ("yaml syntax", "body: [1, 2\nmass: 3\n", "YAML error"),
    ("yaml object tag", "body: !!python/object/apply:os.system ['echo hi']\n", "YAML error"),
    ("not a table", "- 1\n- 2\n", "the top level must be a table"),
], ids=lambda x: x if isinstance(x, str) and len(x) < 20 else None)
def test_unparsable_decks(tmp_path, name, text, expected):
    deck = tmp_path / ("d.toml" if name.startswith("toml") else "d.yaml")
    deck.write_text(text)
    out = tmp_path / "out"
    code, _, err = run("run", deck, "--out", out)
    _check_clean_failure(code, out, err, expected, n_lines=1)
    if name == "toml syntax":
        assert "line 1" in err


@pytest.mark.parametrize("name, content, expected", [
    ("missing record", None, "no such file"),
    ("empty record", "", "the file is empty"),
    ("nan in record", "0,1\n0.01,nan\n0.02,1\n", "not a finite number"),
    ("inf in record", "0,1\n0.01,inf\n0.02,1\n", "not a finite number"),
    ("text in record", "0,1\n0.01,abc\n0.02,1\n", "not a number"),
    ("ragged record", "0,1\n0.01,2,3\n", "3 columns"),
    ("non-uniform time", "0,1\n0.01,2\n0.03,1\n", "not uniform"),
    ("broken at2", "HEADER\nNO COUNTS\n0.1 0.2\n", "NPTS"),
    ("binary record", b"\x89PNG\r\n\x1a\n\xff\xfe\x00", "cannot be read"),
    ("record is a folder", "folder", "cannot be read"),
])
def test_bad_records(tmp_path, name, content, expected):
    fname = "rec.at2" if "at2" in name else "rec.csv"
    if content == "folder":
        (tmp_path / fname).mkdir()
    elif isinstance(content, bytes):
        (tmp_path / fname).write_bytes(content)
    elif content is not None:
        (tmp_path / fname).write_text(content)
    data = copy.deepcopy(seed_deck())
    data["excitation"]["support"]["x1"] = {"file": fname, "units": "g"}
    out = tmp_path / "out"
    code, _, err = run("run", write_deck(tmp_path, data), "--out", out)
    _check_clean_failure(code, out, err, expected, n_lines=1)
    assert "excitation.support.x1" in err


def test_a_failed_run_leaves_previous_results_untouched(tmp_path):
    deck = write_deck(tmp_path, seed_deck(duration=0.1))
    out = tmp_path / "out"
    assert run("run", deck, "--out", out, "--no-plots")[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    bad = copy.deepcopy(seed_deck(duration=0.1))
    bad["excitation"]["support"]["x1"] = {"file": "missing.csv", "units": "g"}
    code, _, _ = run("run", write_deck(tmp_path, bad, name="bad"), "--out", out)
    assert code == 2
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".out")] == []


@pytest.mark.parametrize("method", ["chang", "newmark", "reference"])
def test_the_kernels_run_as_plain_python_too(tmp_path, method):
    """NUMBA_DISABLE_JIT=1 runs the same code uncompiled and gives the same numbers."""
    import os

    data = seed_deck(duration=0.1)
    deck = write_deck(tmp_path, data)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    for name, environ in (("py", env), ("jit", None)):
        subprocess.run([sys.executable, "-m", "rbhyst", "run", str(deck), "--no-plots", "--integrator", method,
                        "--out", str(tmp_path / name)], check=True, capture_output=True, env=environ, cwd=tmp_path)
    py = np.loadtxt(tmp_path / "py" / "time_history.csv", delimiter=",", skiprows=1)
    jit = np.loadtxt(tmp_path / "jit" / "time_history.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(py, jit, rtol=1e-9, atol=1e-12 * np.max(np.abs(jit)))


def test_a_run_without_an_estimate_says_so(tmp_path):
    """Switching the estimate off leaves no doubt: the console says the error was not estimated."""
    path = write_deck(tmp_path, seed_deck(duration=0.5, estimate_error=False))
    code, out, err = run("run", path, "--no-plots")
    assert code == 0, err
    assert "; error not estimated (analysis.estimate_error = false)" in err
    assert json.loads((tmp_path / "results" / "deck" / "summary.json").read_text())["accuracy"] is None


def test_help_shows_units_in_brackets():
    """Units written "[s]" in a help text are units, not markup to swallow."""
    from typer.testing import CliRunner

    from rbhyst.cli import app

    res = CliRunner().invoke(app, ["run", "--help"])
    assert res.exit_code == 0 and "Override analysis.dt [s]." in " ".join(res.stdout.split())


@pytest.mark.parametrize("deck_keys, options, adaptive", [
    ({}, (), False), ({}, ("--integrator", "adaptive"), True), ({}, ("--tolerance", "0.01"), True),
    ({"integrator": "adaptive"}, (), True), ({"tolerance": 0.01}, (), True)])
def test_the_compiling_note_asks_only_for_the_loop_the_run_takes(tmp_path, monkeypatch, deck_keys, options, adaptive):
    """Where numba's JIT compiles the kernels, the note is said while the loop the run takes (the
    deck's method, or the command's) is not in numba's cache; not for a kernel the run may never
    reach (the adaptive loop of a user of chang): it would be said at every run."""
    from rbhyst.solve.kernels import compiled

    asked = []
    monkeypatch.setattr(compiled, "ahead_of_time", lambda: False)  # (the run itself keeps its kernels)
    monkeypatch.setattr(compiled, "cached", lambda dispatchers: asked.append(dispatchers) and False)
    path = write_deck(tmp_path, seed_deck(duration=0.2, **deck_keys))
    code, out, err = run("run", path, "--no-plots", *options)
    assert code == 0, err
    assert [[d.py_func.__name__ for d in ds] for ds in asked] == [["_integrate" if adaptive else "run_chunk"]]
    assert err.count("note: compiling the numba kernels, once") == 1


def test_a_bad_deck_is_not_told_of_compiling(tmp_path, monkeypatch):
    from rbhyst.solve.kernels import compiled

    monkeypatch.setattr(compiled, "cached", lambda dispatchers: False)
    path = write_deck(tmp_path, {**seed_deck(), "body": {"mass": -1.0}})
    code, out, err = run("run", path, "--no-plots")
    assert code == 2 and "compiling" not in err, err
