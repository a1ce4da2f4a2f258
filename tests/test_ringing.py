"""summary.json's ``rang``: the frequency the body rang at after the excitation, from its response
(rbhyst.solve.ringing): a linear body at its mode, and a body on a WRI-like VRM mount against the
free vibration of that single degree of freedom integrated here (scipy, the VRM branch by branch,
each reversal an event)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import linear_set, write_deck
from scipy.integrate import solve_ivp

import rbhyst

WRI_LIKE = {"kb": 2.0e4, "f0": 800.0, "alpha": 200.0}
MASS, PULSE_S = 200.0, 0.01


def body_on(mount: dict, peak_n: float, duration: float = 6.0) -> dict:
    """A 0.5 m square of 200 kg on one mount along x1 through G (u1 alone moves) and two stiff
    linear springs along x2; a half-sine force pulse along x1 at G."""
    return {
        "body": {"vertices": [[-0.25, -0.25], [0.25, -0.25], [0.25, 0.25], [-0.25, 0.25]], "mass": MASS},
        "hysteresis": {"mount": mount, "stiff": linear_set(1e6)},
        "elements": [{"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "mount"},
                     {"point": [0.25, 0.0], "angle_deg": 90.0, "hysteresis": "stiff"},
                     {"point": [-0.25, 0.0], "angle_deg": 90.0, "hysteresis": "stiff"}],
        "excitation": {"force": {"point": [0.0, 0.0], "p1": {"type": "half-sine", "amplitude": peak_n, "units": "N",
                                                             "duration": PULSE_S}}},
        "analysis": {"dt": 1e-3, "duration": duration},
        "output": {"plots": False},
    }


def test_a_linear_body_rings_at_its_mode(tmp_path):
    res = rbhyst.run(write_deck(tmp_path, body_on(linear_set(5e4), 500.0, duration=3.0)))
    rang = res.summary()["rang"]
    assert rang["free_from_s"] == pytest.approx(PULSE_S)
    u1 = rang["coordinates"]["u1"]
    f = math.sqrt(5e4 / MASS) / (2 * math.pi)
    assert u1["frequency_hz"] == pytest.approx(f, rel=1e-3)
    assert u1["first_cycle_hz"] == pytest.approx(f, rel=1e-3) and u1["last_cycle_hz"] == pytest.approx(f, rel=1e-3)
    assert rang["coordinates"]["u2"]["frequency_hz"] is None


def vrm_free_vibration(peak_n: float, t_end: float) -> np.ndarray:
    """Reversal times of m u'' + f(u) = p(t) from rest, f the symmetric VRM of WRI_LIKE along
    eq. 14, f = c_s(u) - g_P exp(-alpha |u - u_P|), c_s = kb u + s f0, a new branch at each
    reversal (u' = 0)."""
    kb, f0, alpha = WRI_LIKE["kb"], WRI_LIKE["f0"], WRI_LIKE["alpha"]
    t, y, s, up, gp = 0.0, np.zeros(2), 1.0, 0.0, f0  # virgin: loading from (0, 0)
    times = []

    def force(u):
        return kb * u + s * f0 - gp * math.exp(-alpha * abs(u - up))

    def rhs(tt, yy):
        p = peak_n * math.sin(math.pi * tt / PULSE_S) if tt < PULSE_S else 0.0
        return [yy[1], (p - force(yy[0])) / MASS]

    def turn(tt, yy):
        return yy[1]
    turn.terminal, turn.direction = True, -s

    while t < t_end:
        turn.direction = -s  # moving the way s says, the velocity crosses zero against it
        sol = solve_ivp(rhs, (t, t_end), y, events=turn, rtol=1e-11, atol=1e-14, max_step=PULSE_S / 4)
        if sol.status != 1:
            break
        t, y = float(sol.t_events[0][0]), sol.y_events[0][0].copy()
        f_at = force(y[0])
        s, up = -s, y[0]
        gp = kb * up + s * f0 - f_at
        y[1] = 0.0
        times.append(t)
    return np.array(times)


def test_a_body_on_a_vrm_mount_rings_as_the_single_degree_of_freedom_does(tmp_path):
    """A pulse that swings the WRI-like mount to 7.7 mm: the rang frequency, and that of its first and
    last cycle (4.3 and 4.76 Hz, where the modes of kb say 1.59 Hz), as the reversals of the exact
    free vibration give them within 2e-3."""
    res = rbhyst.run(write_deck(tmp_path, body_on({"loading": WRI_LIKE, "unloading": WRI_LIKE}, 14000.0)))
    summary = res.summary()
    u1 = summary["rang"]["coordinates"]["u1"]
    times = vrm_free_vibration(14000.0, 6.0)
    times = times[(times >= u1["from_s"] - 0.01) & (times <= u1["to_s"] + 0.01)]
    assert len(times) - 1 == u1["half_cycles"]
    assert u1["frequency_hz"] == pytest.approx((len(times) - 1) / (2 * (times[-1] - times[0])), rel=2e-3)
    assert u1["first_cycle_hz"] == pytest.approx(1 / (times[2] - times[0]), rel=2e-3)
    assert u1["last_cycle_hz"] == pytest.approx(1 / (times[-1] - times[-3]), rel=2e-3)
    assert summary["modes"]["frequencies_hz"][0] == pytest.approx(math.sqrt(2e4 / MASS) / (2 * math.pi))
    assert u1["first_cycle_hz"] > 2.5 * summary["modes"]["frequencies_hz"][0]


def test_no_free_part_no_frequency(tmp_path):
    deck = body_on(linear_set(5e4), 500.0, duration=1.0)
    deck["excitation"]["force"]["p1"] = {"type": "sine", "amplitude": 100.0, "units": "N", "frequency_hz": 3.0}
    rang = rbhyst.run(write_deck(tmp_path, deck)).summary()["rang"]
    assert rang["coordinates"] is None and "does not end" in rang["why"]
