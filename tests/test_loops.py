"""rbhyst calibrate-plot: VRM loops of the seed's Table 1 (Fig. 2) and Table 3 (Fig. 4) sets.

The numbers are derived by hand from eq. 14: along a branch started at (u_P, f_P)
the force is c_s(u) - (c_s(u_P) - f_P) exp(-alpha |u - u_P|).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from rbhyst.analyses.calibration import cycles_of, loop_result, protocol
from rbhyst.cli import app
from rbhyst.model.deck import Loops, load_deck
from rbhyst.model.hysteresis import limiting_curve

DECKS = Path(__file__).resolve().parents[1] / "decks"
FIG2 = DECKS / "seed_fig2_loops.toml"
FIG4 = DECKS / "seed_fig4_loops.toml"

# the seed's tables, typed in again so that the shipped decks are checked against them
TABLE1 = {  # set: (loading, unloading) as kb, f0, alpha, beta1, beta2, gamma1, gamma2, gamma3
    "fig2a_asymmetric": ([0.5, 2.0, 10, 0, 0, 0, 0, 0], [0.0, 2.0, 10, 0, 0, 0, 0, 0]),
    "fig2b_pinched": ([0.5, 2.0, 10, 0, 0, 0.5, 4.0, 0.5], [0.5, 2.0, 10, 0, 0, 0.5, 4.0, -0.5]),
    "fig2c_s_shaped": ([0.5, 1.0, 10, 0, 0, 2.0, 2.0, 0], [0.5, 1.0, 10, 0, 0, 2.0, 2.0, 0]),
    "fig2d_flag_shaped": ([0.5, 1.0, 10, 0, 0, 2.0, 40, 0], [0.5, 1.0, 10, 0, 0, 2.0, 40, 0]),
}
TABLE3 = {
    "wri_axial": ([500000, -500, 1800, 2500, 230, 0, 0, 0], [550000, 4215, 1700, 1400, 200, 0, 0, 0]),
    "wri_shear": ([220000, 1150, 680, 100, 300, 0, 0, 0], [240000, 1044, 700, -100, -300, 0, 0, 0]),
}


def table_set(row) -> np.ndarray:
    return np.array(row, dtype=float)


def shoelace(u: np.ndarray, f: np.ndarray) -> float:
    """Signed area of the polygon (u_i, f_i), counter-clockwise positive (a dissipating loop,
    loading along the top, runs clockwise: its area is -shoelace)."""
    return 0.5 * float(np.sum(u * np.roll(f, -1) - np.roll(u, -1) * f))


# --------------------------------------------------------------------------- decks and protocol


@pytest.mark.parametrize("path, table", [(FIG2, TABLE1), (FIG4, TABLE3)])
def test_shipped_decks_hold_the_seed_tables(path, table):
    deck = load_deck(path)
    assert set(deck.hysteresis) == set(table)
    for name, rows in table.items():
        np.testing.assert_array_equal(deck.hysteresis[name].array(), table_set(rows))


def test_default_protocol_is_the_seeds_sinusoid():
    t, u = protocol(None)
    assert u.size == 2 * 2000 + 1 and t[-1] == pytest.approx(2.0)
    np.testing.assert_allclose(u, 1.5 * np.sin(2 * np.pi * t), atol=1e-12)
    assert u[500] == pytest.approx(1.5) and u[1500] == pytest.approx(-1.5) and u[-1] == 0.0


def test_growing_amplitudes_protocol():
    t, u = protocol(Loops(amplitude=[1.0, 2.0], frequency_hz=2.0, cycles=3, points_per_cycle=40))
    assert u.size == 2 * 3 * 40 + 1 and t[-1] == pytest.approx(3.0)  # 6 cycles at 2 Hz
    assert u[:120].max() == pytest.approx(1.0) and u[120:].max() == pytest.approx(2.0)
    assert np.all(np.abs(np.diff(u)) < 2 * np.pi * 2.0 / 40 * 1.01)  # no jump between amplitudes


# --------------------------------------------------------------------------- Table 1 set 2a by hand


def test_asymmetric_loop_follows_eq14_by_hand():
    """Set 2a: c+(u) = 0.5 u + 2, c-(u) = -2; amplitude A = 1.5, alpha = 10."""
    p = table_set(TABLE1["fig2a_asymmetric"])
    A, a = 1.5, 10.0
    _, u = protocol(None)
    res = loop_result("2a", p, u)
    c_plus = lambda x: 0.5 * x + 2.0  # noqa: E731
    f1 = c_plus(A) - c_plus(0.0) * math.exp(-a * A)  # first peak, from the virgin state
    f_min = -2.0 - (-2.0 - f1) * math.exp(-2 * a * A)  # after the first reversal, at u = -A
    f2 = c_plus(A) - (c_plus(-A) - f_min) * math.exp(-2 * a * A)  # at u = A after a full cycle
    assert res.f[500] == pytest.approx(f1, rel=1e-12)
    assert res.f[1500] == pytest.approx(f_min, rel=1e-12)
    assert res.f[2500] == pytest.approx(f2, rel=1e-12)
    assert f2 == pytest.approx(2.75, abs=1e-12)
    # after a reversal the branch tends to the limiting curve (eq. 14 sample by sample) ...
    down = slice(500, 1500)  # reversal at u = A
    np.testing.assert_allclose(res.f[down], -2.0 - (-2.0 - f1) * np.exp(-a * (A - u[down])), atol=1e-12)
    up = slice(1500, 2500)  # reversal at u = -A
    np.testing.assert_allclose(res.f[up], c_plus(u[up]) - (c_plus(-A) - f_min) * np.exp(-a * (u[up] + A)),
                               atol=1e-12)
    # ... and is on it, to 2e-6, from u = 0 on: c-(u) = -2, c+(u) = 0.5 u + 2
    np.testing.assert_allclose(res.f[1000:1500], -2.0, atol=2e-6)
    np.testing.assert_allclose(res.f[2000:2500], c_plus(u[2000:2500]), atol=2e-6)


def test_energy_dissipated_per_cycle_is_the_loop_area():
    """2a by hand: area = int (c+ - c-) du - gap+/alpha - gap-/alpha = 12 - 0.325 - 0.475 = 11.2;
    2c and 2d: the gamma term is the same on both branches, so 2 f0 2A - 2 (2 f0)/alpha = 5.6.
    The cycle starts at the first peak, reached from the virgin state, whose gap c+(0) = f0
    has decayed only to f0 exp(-alpha A): it adds f0 exp(-alpha A)/alpha to the area."""
    deck = load_deck(FIG2)
    _, u = protocol(deck.loops)
    tail = math.exp(-15.0) / 10.0
    expected = {"fig2a_asymmetric": 11.2 + 2 * tail, "fig2c_s_shaped": 5.6 + tail, "fig2d_flag_shaped": 5.6 + tail}
    for name, hs in deck.hysteresis.items():
        res = loop_result(name, hs.array(), u)
        (cycle,) = res.cycles  # two sine cycles hold one peak-to-peak cycle
        assert (cycle.start, cycle.end) == (500, 2500) and cycle.closed
        area = -shoelace(u[cycle.start:cycle.end], res.f[cycle.start:cycle.end])
        assert area > 0  # clockwise: the element dissipates
        assert cycle.work == pytest.approx(area, rel=2e-5)
        if name in expected:
            assert cycle.work == pytest.approx(expected[name], abs=1e-12)
        # the cumulative work is the integral of f du (trapezoids converge to the closed form)
        trap = float(np.sum(0.5 * (res.f[1:] + res.f[:-1]) * np.diff(u)))
        assert res.work[-1] == pytest.approx(trap, rel=1e-4)


@pytest.mark.parametrize("name", list(TABLE1))
def test_loops_close_once_stable(name):
    p = table_set(TABLE1[name])
    t, u = protocol(Loops(amplitude=1.5, cycles=4, points_per_cycle=400))
    res = loop_result(name, p, u)
    cycles = res.cycles
    assert len(cycles) == 3 and all(c.closed for c in cycles)
    # the first peak comes from the virgin state: its gap has decayed by exp(-alpha A) only
    assert abs(cycles[0].closure) < 4.0 * math.exp(-15.0)
    assert abs(cycles[1].closure) < 1e-12 * np.ptp(res.f)
    assert abs(cycles[2].closure) < 1e-12 * np.ptp(res.f)
    # once stable, successive cycles retrace the same loop sample by sample
    np.testing.assert_allclose(res.f[100:500], res.f[500:900], atol=4.0 * math.exp(-15.0))
    np.testing.assert_allclose(res.f[500:900], res.f[900:1300], atol=1e-12 * np.ptp(res.f))
    assert cycles[0].work == pytest.approx(cycles[1].work, rel=1e-6)


def test_pinched_and_flag_shapes():
    """2b passes near the origin with a small slope (pinched); 2d jumps at u = 0 (flag)."""
    deck = load_deck(FIG2)
    _, u = protocol(deck.loops)
    b = loop_result("b", deck.hysteresis["fig2b_pinched"].array(), u)
    d = loop_result("d", deck.hysteresis["fig2d_flag_shaped"].array(), u)
    # 2b: the loading branch from the reversal at u = -1.5 reaches u = 0 at
    # c+(0) - (c+(-1.5) - f(-1.5)) e^-15, with c+(u) = 0.5 u + 2 + tanh(2 (u - 0.5))
    c_plus = lambda x: 0.5 * x + 2.0 + math.tanh(2.0 * (x - 0.5))  # noqa: E731
    expected = c_plus(0.0) - (c_plus(-1.5) - b.f[1500]) * math.exp(-15.0)
    assert b.f[2000] == pytest.approx(expected, abs=1e-12)
    assert c_plus(0.0) == pytest.approx(2.0 - math.tanh(1.0))  # well below f0 = 2: pinched
    # 2d: between u = -0.1 and 0.1 the loading branch rises by about 4 gamma1 tanh(2) = 7.7
    i_lo, i_hi = 2000 - 21, 2000 + 21  # u = 1.5 sin(2 pi t) = -/+ 0.099 at t = 1 -/+ 21/2000
    rise = d.f[i_hi] - d.f[i_lo]
    assert rise == pytest.approx(
        limiting_curve(d.p, 1, u[i_hi]) - limiting_curve(d.p, 1, u[i_lo]), rel=1e-3)
    assert rise > 7.0


def test_table3_forces_at_the_extremes():
    deck = load_deck(FIG4)
    _, u = protocol(deck.loops)
    assert u.max() == pytest.approx(0.010) and u.min() == pytest.approx(-0.010)
    for name in TABLE3:
        p = deck.hysteresis[name].array()
        res = loop_result(name, p, u)
        i_max, i_min = int(np.argmax(u)), int(np.argmin(u))
        # after reversals 2 x 10 mm away the gap has decayed by exp(-alpha 0.02) < 1e-5
        assert res.f[i_max] == pytest.approx(float(limiting_curve(p, 1, 0.01)), rel=1e-5)
        assert res.f[i_min] == pytest.approx(float(limiting_curve(p, -1, -0.01)), rel=1e-5)
    axial = loop_result("a", deck.hysteresis["wri_axial"].array(), u)
    # c+(10 mm) = 5e5 0.01 - 500 + 2500 (e^2.3 - 1), c-(-10 mm) = -5.5e5 0.01 - 4215 + 1400 (e^-2 - 1)
    assert axial.f.max() == pytest.approx(5000 - 500 + 2500 * math.expm1(2.3), rel=1e-5)
    assert axial.f.min() == pytest.approx(-5500 - 4215 + 1400 * math.expm1(-2.0), rel=1e-5)


def test_cycles_of_skips_noise():
    t, u = protocol(Loops(amplitude=1.0, cycles=3, points_per_cycle=400))
    noisy = u + np.random.default_rng(0).normal(0.0, 0.005, u.size)
    f = np.zeros_like(u)
    assert len(cycles_of(noisy, f, f)) == 2


# --------------------------------------------------------------------------- the command


def run_cli(*args):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_calibrate_plot_fig2(tmp_path):
    out = tmp_path / "fig2"
    r = run_cli("calibrate-plot", FIG2, "--out", out)
    assert r.exit_code == 0, r.output
    assert (out / "loops.png").stat().st_size > 20000
    assert not (out / "fit.json").exists()  # no data, no fit
    summary = json.loads((out / "summary.json").read_text())
    a = summary["sets"]["fig2a_asymmetric"]
    assert a["dissipated_per_cycle_J"] == [pytest.approx(11.2, abs=1e-6)]
    assert a["hysteretic_work_J"] > 11.2
    for name in TABLE1:
        lines = (out / f"loops_{name}.csv").read_text().splitlines()
        assert lines[0] == "u,f" and len(lines) == 1 + 4001
    assert "fig2a_asymmetric: hysteretic work" in r.stderr
    assert not list(tmp_path.glob(".*partial"))


def test_calibrate_plot_selected_set_and_default_folder(tmp_path):
    deck = tmp_path / "wri.toml"
    deck.write_text(FIG4.read_text())
    r = run_cli("calibrate-plot", deck, "--set", "wri_shear")
    assert r.exit_code == 0, r.output
    out = tmp_path / "results" / "wri-loops"
    assert sorted(p.name for p in out.iterdir()) == [".rbhyst.json", "loops.png", "loops_wri_shear.csv",
                                                     "summary.json"]
    r = run_cli("calibrate-plot", deck, "--set", "nope", "--out", tmp_path / "x")
    assert r.exit_code == 2 and r.stderr.startswith("error: ") and "nope" in r.stderr
    assert not (tmp_path / "x").exists()


def test_calibrate_plot_with_data_reports_the_fit(tmp_path):
    """Data made by the shear set itself, written in mm and kN: the set fits them exactly;
    the axial set does not."""
    deck = load_deck(FIG4)
    t, u = protocol(Loops(amplitude=[0.004, 0.008], cycles=2, points_per_cycle=200))
    f = loop_result("s", deck.hysteresis["wri_shear"].array(), u).f
    data = tmp_path / "shear_test.csv"
    rows = "\n".join(f"{ti:.5f},{ui * 1e3:.9g},{fi / 1e3:.9g}" for ti, ui, fi in zip(t, u, f))
    data.write_text("time [s],displacement [mm],force [kN]\n" + rows + "\n")
    out = tmp_path / "fit"
    r = run_cli("calibrate-plot", FIG4, "--data", data, "--out", out)
    assert r.exit_code == 0, r.output
    fit = json.loads((out / "fit.json").read_text())["sets"]
    assert fit["wri_shear"]["nrmse"] < 1e-7 and fit["wri_shear"]["r2"] > 1 - 1e-12
    assert fit["wri_axial"]["nrmse"] > 0.05
    table = np.loadtxt(out / "loops_wri_shear.csv", delimiter=",", skiprows=1)
    assert (out / "loops_wri_shear.csv").read_text().startswith("u,f,f_data\n")
    np.testing.assert_allclose(table[:, 0], u, atol=1e-12)
    np.testing.assert_allclose(table[:, 2], f, rtol=1e-8, atol=1e-6)
    assert "NRMSE" in r.stderr
