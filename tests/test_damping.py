"""Rayleigh damping from the initial system's modes: the ratios asked for at the two frequencies
(measured by the logarithmic decrement of a free decay), its work in the energy balance, and
its mistakes as one line each."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rbhyst
from rbhyst.errors import InputError
from conftest import invoke, square_linear_deck, write_deck

K, MASS, SIDE = 2.0e5, 500.0, 1.0
#: the square's decoupled modes: translations sqrt(2k/m), rotation sqrt(4k (s/2)^2 / J), J = m s^2 / 6
W_TRANSLATION = math.sqrt(2 * K / MASS)
W_ROTATION = math.sqrt(4 * K * (SIDE / 2) ** 2 / (MASS * SIDE**2 / 6))


def decay_deck(rayleigh: dict, duration: float = 2.5) -> dict:
    """The square on linear springs, struck by a short force along x1 and a short moment at G,
    then free: u1 rings at the translation mode, theta3 at the rotation mode."""
    data = square_linear_deck(K, MASS, SIDE)
    pulse = {"type": "half-sine", "duration": 0.01}
    data["excitation"] = {"force": {"point": [0.0, 0.0], "p1": {**pulse, "amplitude": 2000.0, "units": "N"},
                                    "m3": {**pulse, "amplitude": 500.0, "units": "N m"}}}
    data["analysis"] = {"dt": 2e-4, "duration": duration, "integrator": "adaptive", "rtol": 1e-10,
                        "estimate_error": False}
    data["damping"] = {"rayleigh": rayleigh}
    return data


def decrement_ratio(t: np.ndarray, x: np.ndarray, after: float) -> float:
    """Damping ratio from the slope of ln |peak| over successive peaks of a free decay
    (delta = 2 pi zeta / sqrt(1 - zeta^2)); each peak refined by a parabola through three rows."""
    y = np.abs(x)
    i = np.where((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]) & (t[1:-1] > after))[0] + 1
    a, b, c = y[i - 1], y[i], y[i + 1]
    peaks = b + (a - c) ** 2 / (8 * (2 * b - a - c))  # the parabola's vertex value
    # |x| peaks every half period: the decrement per half period is delta / 2
    slope = np.polyfit(np.arange(len(peaks)), np.log(peaks), 1)[0]
    delta = -2.0 * slope
    return delta / math.sqrt(4 * math.pi**2 + delta**2)


@pytest.mark.parametrize("rayleigh", [
    {"ratio": 0.05, "modes": [1, 3]},
    {"ratio": [0.04, 0.06], "frequencies_hz": [W_TRANSLATION / (2 * math.pi), W_ROTATION / (2 * math.pi)]},
], ids=["modes", "frequencies"])
def test_free_decay_gives_the_ratios_at_the_two_frequencies(tmp_path, rayleigh):
    res = rbhyst.run(write_deck(tmp_path, decay_deck(rayleigh)))
    want = rayleigh["ratio"] if isinstance(rayleigh["ratio"], list) else [rayleigh["ratio"]] * 2
    zeta_u = decrement_ratio(res.time, res.column("u1_m"), after=0.02)
    zeta_theta = decrement_ratio(res.time, res.column("theta3_rad"), after=0.02)
    assert zeta_u == pytest.approx(want[0], rel=1e-6)
    assert zeta_theta == pytest.approx(want[1], rel=1e-6)
    ray = res.summary()["rayleigh"]
    np.testing.assert_allclose(sorted(ray["mode_frequencies_hz"]),
                               np.array([W_TRANSLATION, W_TRANSLATION, W_ROTATION]) / (2 * math.pi), rtol=1e-12)
    np.testing.assert_allclose([ray["mode_ratios"][0], ray["mode_ratios"][2]], want, rtol=1e-12)
    # its work is in the balance, and it is the work of C v: integral of v^T (a0 M + a1 K) v dt
    e_in, e_visc = res.column("E_input_J"), res.column("E_viscous_J")
    assert res.energy_balance < 1e-6
    assert np.all(np.abs(res.column("E_error_J")) <= 1e-6 * e_in.max())
    c = ray["a0_1_s"] * np.diag([MASS, MASS, MASS * SIDE**2 / 6]) + ray["a1_s"] * np.diag([2 * K, 2 * K, K * SIDE**2])
    v = np.column_stack([res.column(n) for n in ("v1_m_s", "v2_m_s", "omega3_rad_s")])
    power = np.einsum("ij,jk,ik->i", v, c, v)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(res.time))])
    np.testing.assert_allclose(e_visc, work, rtol=0, atol=1e-4 * e_in.max())
    assert e_visc[-1] > 0.99 * e_in[-1]  # by the end it has taken nearly all that went in


@pytest.mark.parametrize("integrator", ["chang", "newmark", "central-difference", "kr-alpha"])
def test_every_integrator_carries_it(tmp_path, integrator):
    data = decay_deck({"ratio": 0.05, "modes": [1, 3]}, duration=1.5)
    data["analysis"].update(integrator=integrator, dt=2.5e-4)
    res = rbhyst.run(write_deck(tmp_path, data))
    assert decrement_ratio(res.time, res.column("u1_m"), after=0.02) == pytest.approx(0.05, rel=0.02)
    assert res.energy_balance < 2e-3 and res.extremes.peak("E_viscous_J") > 0.9 * res.extremes.peak("E_input_J")
    assert "d1_f_N" not in res.columns  # Rayleigh damping has no damper columns


@pytest.mark.parametrize("rayleigh, line", [
    ({"ratio": 0.05}, "damping.rayleigh: give exactly one of `frequencies_hz`"),
    ({"ratio": 0.05, "modes": [1, 3], "frequencies_hz": [1.0, 2.0]}, "damping.rayleigh: give exactly one of"),
    ({"ratio": 0.05, "modes": [2, 2]}, "damping.rayleigh.modes: [2, 2]: two different modes"),
    ({"ratio": 0.05, "modes": [1, 4]}, "damping.rayleigh.modes[2]: must be less than or equal to 3"),
    ({"ratio": 1.5, "modes": [1, 3]}, "damping.rayleigh.ratio"),
    ({"ratio": [0.2, 0.001], "frequencies_hz": [1.0, 2.0]}, "damping.rayleigh.ratio: [0.2, 0.001] at [1.0, 2.0] Hz"),
    ({"ratio": 0.05, "frequencies_hz": [1.0, 2.0], "kind": "x"}, "damping.rayleigh.kind: unknown key"),
])
def test_mistakes_are_one_line_naming_the_key(tmp_path, rayleigh, line):
    data = decay_deck(rayleigh, duration=0.1)
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots")
    assert code == 2
    assert "Traceback" not in err
    assert any(x.startswith("error: " + line) for x in err.splitlines()), err


def test_without_it_nothing_changes(tmp_path):
    data = decay_deck({"ratio": 0.05, "modes": [1, 3]}, duration=0.3)
    del data["damping"]
    res = rbhyst.run(write_deck(tmp_path, data))
    assert "E_viscous_J" not in res.columns and "rayleigh" not in res.summary()
    with pytest.raises(InputError):
        rbhyst.load_deck(write_deck(tmp_path, {**data, "damping": {"rayleigh": {"ratio": 0.0, "modes": [1, 2]}}}, "z"))
