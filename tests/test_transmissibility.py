"""Stepped-sine transmissibility against closed forms, and the command."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import rbhyst.analyses.transmissibility as tr
from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.errors import InputError
from rbhyst.analyses.transmissibility import steady_state, stepped_sine
from conftest import DECKS, square_linear_deck, write_deck

K, MASS = 2.0e5, 500.0
W0 = math.sqrt(2 * K / MASS)  # the square's translation along x1: two springs of k
F0 = W0 / (2 * math.pi)


def linear_square(integrator: str = "adaptive") -> dict:
    d = square_linear_deck(k=K, mass=MASS)
    d["analysis"]["integrator"] = integrator
    d["output"] = {"points": [{"name": "corner", "point": [0.5, 0.5]}]}
    return d


# ratios where the ramp's free vibration vanishes: its envelope's slope is a Hann window of
# RAMP_CYCLES / f, whose spectrum is zero where RAMP_CYCLES |1 - 1/r| is a whole number >= 2
# (elsewhere it leaves about 1e-4: r = 3 gives 2e-4)
RATIOS = (0.1, 0.5, 0.8, 1.25, 2.0, 5.0)


def test_the_ramps_free_vibration_vanishes_at_these_ratios():
    assert tr.RAMP_CYCLES == 20
    for r in RATIOS:
        k = tr.RAMP_CYCLES * abs(1 - 1 / r)
        assert abs(k - round(k)) < 1e-9 and round(k) >= 2


def test_a_ramped_sine_rises_smoothly_then_is_the_sine():
    from rbhyst.model.signals import ramp_envelope, sine

    f, amp = 4.0, 2.5
    s, plain = sine(amp, f, start=0.1, ramp_cycles=3), sine(amp, f, start=0.1)
    t = np.linspace(0, 2, 4001)
    after = t >= 0.1 + 3 / f
    np.testing.assert_array_equal(s(t)[after], plain(t)[after])
    tau = (t[~after] - 0.1) / (3 / f)
    np.testing.assert_allclose(s(t)[~after], np.where(tau >= 0, amp * (tau - np.sin(2 * np.pi * tau) / (2 * np.pi))
                                                      * np.sin(2 * np.pi * f * (t[~after] - 0.1)), 0), atol=1e-15)
    assert s.breakpoints == (0.1, 0.1 + 3 / f)
    # zero slope and curvature at both ends: the envelope departs from 0 and 1 as (2 pi)^2 h^3 / 6
    h = 1e-3
    assert ramp_envelope(h) == pytest.approx(4 * np.pi**2 * h**3 / 6, rel=1e-4)
    assert 1 - ramp_envelope(1 - h) == pytest.approx(4 * np.pi**2 * h**3 / 6, rel=1e-4)
    with pytest.raises(InputError, match=r"ramp_cycles: must be greater than or equal to 0"):
        d = square_linear_deck()
        d["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 2.0, "units": "g",
                                              "ramp_cycles": -1.0}}}
        parse_deck(d)


def test_undamped_linear_transmissibility_is_the_closed_form():
    """T = 1 / |1 - r^2| (a linear spring: equal VRM branches with f0 = 0), no cross term.

    Tolerance: the adaptive integration at rtol 1e-8 and the parabola through the largest
    sample (at most 3.7e-7 low on a sinusoid at 100 samples a period) leave 1e-6.
    """
    deck = parse_deck(linear_square())
    res = stepped_sine(deck, "x1", [1.5], [r * F0 for r in RATIOS])
    for row in res.table():
        r = row[0] / F0
        t = dict(zip(res.columns, row[2:]))
        assert t["T_G_x1"] == pytest.approx(1 / abs(1 - r * r), rel=1e-6), r
        assert t["T_corner_x1"] == pytest.approx(t["T_G_x1"], rel=1e-9)  # no rotation: the corner moves as G
        # cos(90 deg) = 6e-17 couples the directions at rounding level: nothing more
        assert t["T_G_x2"] < 1e-12 and t["T_corner_x2"] < 1e-12
    assert all(run.settled and run.cycles == 2 * tr.WINDOW for run in res.runs)
    assert res.table()[0, 2] == pytest.approx(1.0, abs=0.011)  # r = 0.1: T -> 1 at low frequency


def test_the_decks_integrator_is_second_order_at_100_steps_a_period():
    """chang at dt = P / 100: the forcing's phase error (omega dt)^2 / 12 shifts r, and
    T = 1 / |1 - r^2| by 2 r^2 / |1 - r^2| times it."""
    deck = parse_deck(linear_square("chang"))
    for r in (0.5, 2.0):
        s = steady_state(deck, "x1", 1.0, r * F0)
        bound = 2 * (2 * math.pi / 100) ** 2 / 12 * 2 * r * r / abs(1 - r * r)
        assert abs(s.T["T_G_x1"] * abs(1 - r * r) - 1) < bound


def test_viscous_damping_closed_form():
    """T = sqrt(1 + (2 zeta r)^2) / sqrt((1 - r^2)^2 + (2 zeta r)^2) with linear viscous
    dampers ([[dampers]])."""
    zeta = 0.1
    c = zeta * 2 * MASS * W0 / 2  # two dampers along x1: 2 c = 2 zeta m omega0
    d = linear_square()
    d["dampers"] = [{"point": [0.0, 0.5], "angle_deg": 0.0, "c": c}, {"point": [0.0, -0.5], "angle_deg": 0.0, "c": c}]
    deck = parse_deck(d)
    res = stepped_sine(deck, "x1", [1.0], [r * F0 for r in (0.5, 1.0, 2.0, 3.0)])
    for row in res.table():
        r = row[0] / F0
        exact = math.sqrt(1 + (2 * zeta * r) ** 2) / math.sqrt((1 - r * r) ** 2 + (2 * zeta * r) ** 2)
        # damped, the start's transient decays as exp(-zeta w t) and the run stops once two windows
        # agree to 0.5 %: what remains of it is some 1e-4 (at r = 1: 9.5e-5), not the integration's
        assert row[2] == pytest.approx(exact, rel=1e-3), r


def test_a_nearly_linear_hysteretic_scene_follows_below_resonance_and_isolates_above():
    """Small loops (f0 = 50 N, 10 % stiffer at reversals) on the springs: hysteretic damping
    only, so the undamped closed form holds only roughly (at resonance such friction-like
    damping cannot bound the response of 1000 N of shaking: Den Hartog's limit)."""
    d = linear_square("chang")
    d["hysteresis"]["lin"] = {"loading": {"kb": K, "f0": 50.0, "alpha": 200.0},
                              "unloading": {"kb": K, "f0": 50.0, "alpha": 200.0}}
    res = stepped_sine(parse_deck(d), "x1", [2.0], [0.1 * F0, 0.5 * F0, 3 * F0])
    assert all(run.settled for run in res.runs)
    for row in res.table():
        r = row[0] / F0
        assert row[2] == pytest.approx(1 / abs(1 - r * r), rel=0.1), r
    low, _, high = res.table()[:, 2]
    assert low == pytest.approx(1.0, abs=0.02) and high < 0.2


def test_pool_and_this_process_give_the_same_numbers():
    deck = parse_deck(linear_square("chang"))
    freqs = [F0 * r for r in (0.3, 0.7, 1.4, 2.2, 3.1, 4.4)]
    one = stepped_sine(deck, "x1", [1.0, 3.0], freqs, workers=1)
    two = stepped_sine(deck, "x1", [1.0, 3.0], freqs, workers=2)
    np.testing.assert_array_equal(one.table(), two.table())


def test_a_response_that_never_settles_is_reported_with_a_note(monkeypatch):
    monkeypatch.setattr(tr, "SETTLE_TOL", 0.0)
    monkeypatch.setattr(tr, "MAX_CYCLES", 4 * tr.WINDOW)
    res = stepped_sine(parse_deck(linear_square("chang")), "x1", [1.0], [3 * F0])
    run, = res.runs
    assert not run.settled and run.cycles == 4 * tr.WINDOW and run.change > 0
    assert res.notes == [f"{3 * F0:g} Hz, 1 m/s2: not steady after 16 cycles (the peaks of the last two "
                         f"4-cycle windows differ by {run.change:.2%}): T is that of the last 4 cycles"]


def test_a_wire_rope_cabinet_follows_the_ground_at_low_frequency():
    deck = parse_deck({**_cabinet(), "output": {"points": [{"name": "top", "point": [0.0, 2.0]}]}})
    s = steady_state(deck, "x1", 0.3 * 9.80665, 0.3)
    assert s.settled
    assert s.T["T_G_x1"] == pytest.approx(1.0, abs=0.01) and s.T["T_top_x1"] == pytest.approx(1.0, abs=0.01)


def _cabinet() -> dict:
    import tomllib

    return tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())


def test_the_command_writes_csv_json_and_plot(tmp_path):
    path = write_deck(tmp_path, linear_square("chang"))
    res = CliRunner().invoke(app, ["transmissibility", str(path), "--direction", "x1", "--amplitude", "0.1,0.2",
                                   "--units", "g", "--from", "2", "--to", "20", "--count", "3", "--workers", "1"])
    assert res.exit_code == 0, res.stderr
    out = tmp_path / "results" / "deck-transmissibility"
    assert sorted(p.name for p in out.iterdir()) == [".rbhyst.json", "transmissibility.csv", "transmissibility.json",
                                                     "transmissibility.png"]
    rows = list(csv.reader((out / "transmissibility.csv").open()))
    assert rows[0] == ["frequency_hz", "amplitude_m_s2", "T_G_x1", "T_G_x2", "T_corner_x1", "T_corner_x2"]
    numbers = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(numbers[:, 0], [2, 2 * 10**0.5, 20] * 2, rtol=1e-9)
    np.testing.assert_allclose(numbers[:, 1], [0.980665] * 3 + [1.96133] * 3, rtol=1e-9)
    r = numbers[:, 0] / F0
    np.testing.assert_allclose(numbers[:, 2], 1 / np.abs(1 - r * r), rtol=2e-3)  # chang (see above)
    summary = json.loads((out / "transmissibility.json").read_text())
    assert summary["direction"] == "x1" and len(summary["runs"]) == 6
    assert summary["method"]["ramp_cycles"] == tr.RAMP_CYCLES
    assert all(run["dt_s"] <= 1 / run["frequency_hz"] / 100 * (1 + 1e-12) and run["dt_s"] <= 1e-3 for run in
               summary["runs"])
    assert "0.980665 m/s2: T_G_x1 from" in res.stderr


@pytest.mark.parametrize("args, lines", [
    (["--direction", "x3", "--amplitude", "1,-1", "--units", "g", "--frequencies", "1,1,0"],
     ["--direction: 'x3': x1 or x2 (x3, the vertical, for a deck in space)", "--amplitude: -1 must be positive", "frequencies: 0 Hz must be positive",
      "frequencies: each frequency once"]),
    (["--direction", "x1", "--amplitude", "1", "--units", "cm/s2", "--frequencies", "1"],
     ["--units: 'cm/s2': g or m/s2"]),
    (["--direction", "x1", "--amplitude", "1", "--units", "g", "--frequencies", "1", "--from", "1"],
     ["--frequencies: give either a list or --from, --to and --count, not both"]),
    (["--direction", "x1", "--amplitude", "1", "--units", "g", "--from", "1"],
     ["frequencies: --frequencies, or --from, --to and --count (--to, --count missing)"]),
    (["--direction", "x1", "--amplitude", "1", "--units", "g", "--from", "5", "--to", "1", "--count", "1"],
     ["--to: 1 Hz must be above --from (5 Hz)", "--count: 1 must be at least 2"]),
])
def test_command_mistakes_one_line_each(tmp_path, args, lines):
    path = write_deck(tmp_path, linear_square("chang"))
    res = CliRunner().invoke(app, ["transmissibility", str(path), *args])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [f"error: {line}" for line in lines]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deck.toml"]
