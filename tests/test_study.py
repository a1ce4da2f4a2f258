"""`rbhyst study`: its files and their contract, its pieces, and its clean failures."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from rbhyst.cli import app

from rbhyst.model.deck import parse_deck
from rbhyst.model.system import assemble
from rbhyst.solve.plan import Settings
from rbhyst.analyses.study import (CSV_COLUMNS, Run, default_dts, fixed_step_names, observed_order, relative_errors, run_study, union_grid, write_csv)
from conftest import DECKS, seed_deck, square_linear_deck, write_deck

runner = CliRunner()


def invoke(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res.exit_code, res.stderr


def test_study_writes_its_files(tmp_path):
    path = write_deck(tmp_path, seed_deck(duration=1.0))
    out = tmp_path / "study"
    code, err = invoke("study", path, "--integrators", "chang,newmark", "--dt", "0.002,0.001,0.0005,0.00025",
                       "--out", out)
    assert code == 0, err
    assert "chang: observed order" in err and "newmark: observed order" in err and "reference: DOP853" in err
    with open(out / "study.csv") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert [(r[0], float(r[1])) for r in rows[1:]] == [
        (m, dt) for m in ("chang", "newmark") for dt in (0.002, 0.001, 0.0005, 0.00025)]
    for r in rows[1:]:
        assert int(r[2]) == round(1.0 / float(r[1]))
        vals = [float(x) for x in r[3:8]]  # wall_s, the three errors, err_max
        assert all(math.isfinite(v) and v > 0 for v in vals)
        assert vals[-1] == max(vals[1:4])
    summary = json.loads((out / "study.json").read_text())
    for m in ("chang", "newmark"):
        assert summary["observed_order"][m]["order"] == pytest.approx(2.0, abs=0.5)
        assert summary["observed_order"][m]["expected"] == 2
    ref = summary["reference"]
    assert ref["method"].startswith("DOP853") and ref["rtol"] == 1e-12
    assert len(ref["atol_q"]) == 3 and "reversal" in ref["events"] and ref["reversals"] > 0
    assert len(summary["runs"]) == 8
    for png in ("error_vs_runtime.png", "error_vs_dt.png"):
        data = (out / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_study_defaults_ladder_and_folder(tmp_path):
    deck = seed_deck(duration=0.3)
    path = write_deck(tmp_path, deck)
    code, err = invoke("study", path, "--integrators", "chang", "--no-plots")
    assert code == 0, err
    out = tmp_path / "results" / "deck-study"  # beside the run's folder, which `run` replaces whole
    with open(out / "study.csv") as fh:
        dts = [float(r["dt_s"]) for r in csv.DictReader(fh)]
    assert dts == pytest.approx(default_dts(1e-3))
    assert default_dts(1e-3) == pytest.approx([4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4])
    assert not list(out.glob("*.png"))


@pytest.mark.parametrize("args, message", [
    (("--integrators", "chang,nope"), "--integrators: unknown 'nope'"),
    (("--integrators", "reference"), "--integrators: 'reference' is what the others are measured against"),
    (("--dt", "0.001,abc"), "--dt: 'abc' is not a number"),
    (("--dt", "0.001,-0.002"), "--dt: -0.002 must be a positive number of seconds"),
    (("--dt", "5"), "--dt: 5 s is longer than the analysis"),
])
def test_study_rejects_bad_options_cleanly(tmp_path, args, message):
    path = write_deck(tmp_path, seed_deck(duration=0.2))
    out = tmp_path / "study"
    code, err = invoke("study", path, *args, "--out", out)
    assert code == 2
    assert err.startswith("error: ") and message in err, err
    assert "Traceback" not in err
    assert not out.exists()


def test_a_failed_run_is_a_row_not_a_crash(tmp_path):
    """Central difference past its stability limit with no substeps allowed: the run stops, the study goes on.
    (A sine slow enough that dt = 3/w follows it without substeps: 0.2 Hz, 47 steps a period.)"""
    deck = square_linear_deck(k=2.0e5, mass=500.0)
    deck["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 0.2,
                                             "units": "m/s2"}}}
    system = assemble(parse_deck(deck), tmp_path)
    w = math.sqrt(4e5 / 500.0)
    settings = Settings(dt=1e-3, duration=40.0, max_substep_level=0, max_omega_dt=10.0)
    seen = []
    study = run_study(system, settings, ["chang", "central-difference"], [3.0 / w, 1e-3],
                      progress=lambda label, done, total: seen.append((done, total)), repeat=1)
    failed = [r for r in study.runs if r.failed]
    assert [(r.integrator, r.dt) for r in failed] == [("central-difference", 3.0 / w)]
    assert "no longer finite" in failed[0].failed
    others = [r for r in study.runs if r is not failed[0]]
    assert all(r.failed is None and math.isfinite(r.err_max) for r in others)
    assert all(r.err_max < 0.05 for r in others if r.dt == 1e-3)
    write_csv(study, tmp_path / "study.csv")
    row = (tmp_path / "study.csv").read_text().splitlines()[3]
    assert row.startswith("central-difference,") and row.endswith(",,,,,")
    # progress: from 0 to all 5 runs (reference included), never backwards
    assert seen[0] == (0, 5) and seen[-1] == (5, 5)
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))


def test_union_grid_of_steps_that_do_not_nest():
    times, index = union_grid({0.003: 4, 0.002: 6})
    assert np.allclose(times, [0, 0.002, 0.003, 0.004, 0.006, 0.008, 0.009, 0.010, 0.012])
    assert np.allclose(times[index[0.003]], 0.003 * np.arange(5))
    assert np.allclose(times[index[0.002]], 0.002 * np.arange(7))


def test_relative_errors_per_coordinate(tmp_path):
    system = assemble(parse_deck(seed_deck(duration=0.1)), tmp_path)
    t = np.linspace(0, 1, 101)
    ref = np.column_stack([np.sin(t), 2 * np.sin(t), 0.0 * t])  # a rotation that never happens
    d = ref + np.column_stack([0.01 * t, 0.01 * t, 1e-4 * t])
    e = relative_errors(d, ref, system)
    assert e[0] == pytest.approx(0.01 / math.sin(1.0))
    assert e[1] == pytest.approx(0.005 / math.sin(1.0))
    rg = math.sqrt(system.mass[2] / system.mass[0])
    assert e[2] == pytest.approx(1e-4 * rg / (2 * math.sin(1.0)))  # against the body's motion


def test_observed_order_uses_the_asymptotic_range():
    runs = [Run("m", dt, errors=(3e3 * dt**2,) * 3) for dt in (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4)]
    runs[0].errors = (0.5, 0.5, 0.5)  # pre-asymptotic
    runs[-1].errors = (1e-10,) * 3  # at the reference's floor
    runs.append(Run("m", 3e-4, failed="stopped"))
    o = observed_order(runs, floor=1e-9)
    assert o["order"] == pytest.approx(2.0)
    assert o["fit_dt_s"] == [1.25e-3, 2.5e-3, 5e-3]
    assert observed_order(runs[:1], floor=1e-9)["order"] is None


def test_every_fixed_step_method_is_studied_by_default():
    assert fixed_step_names() == ["chang", "central-difference", "newmark", "kr-alpha"]


def test_study_shows_each_run_s_estimate_against_its_true_error(tmp_path):
    deck = DECKS / "machine_on_mounts.toml"
    out = tmp_path / "st"
    res = CliRunner().invoke(app, ["study", str(deck), "--integrators", "chang,newmark", "--dt", "0.004,0.002,0.001",
                                   "--out", str(out), "--no-plots"])
    assert res.exit_code == 0, res.stderr
    rows = (out / "study.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert header[-2:] == ["est_max", "est_over_true"]
    for line in rows[1:]:
        cells = dict(zip(header, line.split(",")))
        assert 0.5 <= float(cells["est_over_true"]) <= 10.0, line


def test_a_deck_with_gravity_is_studied_from_its_static_equilibrium():
    """The runs start at rest at the static equilibrium under the weight: the reference and the
    estimate's solution do too, and are measured from it as the runs' tables are."""
    data = seed_deck(duration=1.0)
    data["body"]["gravity"] = [0.0, -9.80665]
    deck = parse_deck(data)
    system = assemble(deck, DECKS)
    study = run_study(system, Settings(dt=0.001, duration=1.0, integrator="chang"), ["chang"], [0.002, 0.001])
    for r in study.runs:
        assert r.failed is None and r.err_max < 0.05, r
        assert 0.9 < r.est_over_true < 1.1, r
