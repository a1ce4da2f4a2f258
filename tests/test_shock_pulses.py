"""Classical pulses as a shaker plays them (rbhyst.model.shock_pulses): compensated so that the
table's velocity and displacement return to zero, the main pulse within its band, the deck's
keys, and a deck that does not ask unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import invoke, write_deck
from scipy.integrate import cumulative_trapezoid
from test_accelerations import pulse_deck

from rbhyst.model import signals
from rbhyst.model.deck import parse_deck
from rbhyst.model.shock_pulses import (
    PULSE_TOLERANCE,
    classical_pulse,
    table_motion,
    tolerance_check,
)
from rbhyst.model.system import assemble

G = 9.80665


def integrated(series, per_sample: int = 8):
    """Velocity and displacement of the series, linear between its samples, by the trapezoidal rule
    on a grid ``per_sample`` times finer (independent of the module's exact formulas)."""
    t = np.linspace(series.t0, series.end, (len(series.values) - 1) * per_sample + 1)
    a = series(t)
    v = cumulative_trapezoid(a, t, initial=0.0)
    return t, a, v, cumulative_trapezoid(v, t, initial=0.0)


@pytest.mark.parametrize("kind", ["half-sine", "terminal-peak-sawtooth", "trapezoid"])
@pytest.mark.parametrize("amplitude, duration", [(20.0 * G, 0.011), (-40.0 * G, 0.006)])
def test_a_compensated_pulse_brings_the_table_to_rest(kind, amplitude, duration):
    p = classical_pulse(kind, amplitude, duration, start=0.01, compensation="pre-post", ratio=0.1)
    _, _, v, x = integrated(p.series)
    assert abs(v[-1]) < 1e-9 * np.abs(v).max()
    assert abs(x[-1]) < 1e-5 * np.abs(x).max()  # (the fine trapezoidal rule's own error on x)
    exact_v, exact_x = table_motion(p.series.values, p.series.dt)
    assert abs(exact_v[-1]) < 1e-12 * np.abs(exact_v).max() and abs(exact_x[-1]) < 1e-12 * np.abs(exact_x).max()
    assert np.abs(exact_x).max() == pytest.approx(np.abs(x).max(), rel=1e-4)
    # the main pulse within the standard's band about its nominal shape, and its velocity change
    check = tolerance_check(p, p.series.times, p.series.values)
    assert check["pass"] and check["deviation"] < 1e-9
    nominal = {"half-sine": 2.0 / math.pi, "terminal-peak-sawtooth": 0.5, "trapezoid": 0.9}[kind] * amplitude * duration
    assert check["velocity_change_m_s"] == pytest.approx(nominal, rel=1e-4)
    # the compensation pulses oppose the main one, the larger at the ratio asked, and begin at start
    assert np.sign(p.pre_peak) == np.sign(p.post_peak) == -np.sign(amplitude)
    assert max(abs(p.pre_peak), abs(p.post_peak)) == pytest.approx(0.1 * abs(amplitude), rel=0.02)
    assert max(abs(p.pre_peak), abs(p.post_peak)) <= PULSE_TOLERANCE["outside"] * abs(amplitude)
    assert p.series.t0 == 0.01 and p.main_start == pytest.approx(0.01 + p.compensation_duration)
    assert (abs(p.pre_peak) == pytest.approx(abs(p.post_peak), rel=1e-9)) == (kind != "terminal-peak-sawtooth")


def test_a_bare_pulse_does_not_come_to_rest_and_a_wrong_one_fails_its_band():
    p = classical_pulse("half-sine", 10.0, 0.01)
    v, _ = table_motion(p.series.values, p.series.dt)
    assert v[-1] == pytest.approx(2.0 / math.pi * 10.0 * 0.01, rel=1e-4)
    played = 1.25 * p.series.values  # 25 % high: outside the +-20 % band
    check = tolerance_check(p, p.series.times, played)
    assert not check["pass"] and check["deviation"] == pytest.approx(0.25, rel=1e-3)
    t = np.linspace(0.0, 0.03, 3001)
    assert tolerance_check(p, t, p.series(t))["pass"]
    ringing = p.series(t) + 0.3 * 10.0 * (t > p.main_end)  # 0.3 A after the pulse
    assert not tolerance_check(p, t, ringing)["pass"]


def test_a_deck_that_does_not_ask_keeps_its_analytic_pulse(tmp_path):
    bare = assemble(parse_deck(pulse_deck("half-sine")), tmp_path).excitation.ag2
    assert isinstance(bare, signals.Pulse)
    asked = assemble(parse_deck(pulse_deck("half-sine", compensation="pre-post")), tmp_path).excitation.ag2
    assert not isinstance(asked, signals.Pulse)
    v, x = table_motion(asked.values, asked.dt)
    assert abs(v[-1]) < 1e-12 and abs(x[-1]) < 1e-12
    trapezoid = assemble(parse_deck(pulse_deck("trapezoid", rise=0.002)), tmp_path).excitation.ag2
    rising = trapezoid(np.array([0.05 + 0.001]))  # half-way up its 2 ms rise
    assert rising[0] == pytest.approx(0.5 * 10.0 * G, rel=1e-9)


@pytest.mark.parametrize("extra, said", [
    ({"type": "trapezoid", "rise": 0.02}, "excitation.support.x2: rise: 0.02 s must be below half the duration"),
    ({"rise": 0.001}, "excitation.support.x2: rise: only a trapezoid has one"),
    ({"compensation_ratio": 0.1}, 'excitation.support.x2: compensation_ratio: only with compensation = "pre-post"'),
    ({"compensation": "pre-post", "compensation_ratio": 0.5}, "excitation.support.x2.compensation_ratio"),
    ({"compensation": "both"}, "excitation.support.x2.compensation"),
])
def test_pulse_keys_mistakes(tmp_path, extra, said):
    data = pulse_deck("half-sine")
    data["excitation"]["support"]["x2"].update(extra)
    code, err = invoke("run", write_deck(tmp_path, data), "--out", tmp_path / "o", "--no-plots")
    assert code == 2 and said in err and len(err.strip().splitlines()) == 1
