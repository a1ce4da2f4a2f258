"""Real equipment: viscous dampers, gravity preload, stroke limits (bodies of parts: test_parts.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import rbhyst
from conftest import linear_set, seed_deck, square_linear_deck, write_deck

K, MASS = 2.0e5, 500.0  # square_linear_deck: the x1 mode has 2K, omega^2 = 2K/M
W = math.sqrt(2 * K / MASS)


def damped_square(zeta: float, excitation=None) -> dict:
    """Four linear springs and two dampers along x1 through G: a damped oscillator along x1."""
    data = square_linear_deck(K, MASS)
    c_total = 2 * zeta * math.sqrt(2 * K * MASS)
    data["dampers"] = [{"point": [0.0, 0.5], "angle_deg": 0.0, "c": c_total / 2},
                       {"point": [0.0, -0.5], "angle_deg": 0.0, "c": c_total / 4, "count": 2}]
    if excitation is not None:
        data["excitation"] = excitation
    return data


@pytest.mark.parametrize("method", ["chang", "central-difference", "newmark", "kr-alpha", "adaptive"])
def test_free_decay_of_a_damped_oscillator(tmp_path, method):
    """A 0.01 s force pulse, then free vibration: u1 decays as exp(-zeta w t) at w_d = w sqrt(1 - zeta^2)."""
    zeta = 0.05
    data = damped_square(zeta, {"force": {"p1": {"type": "half-sine", "amplitude": 2000.0, "units": "N",
                                                 "duration": 0.01}}})
    data["analysis"] = {"dt": 2e-4, "duration": 1.0}
    res = rbhyst.run(write_deck(tmp_path, data), integrator=method)
    t, u = res.time, res.column("u1_m")
    free = t > 0.05
    # exact free response from the state just after the pulse (fitted at t = 0.05)
    wd = W * math.sqrt(1 - zeta**2)
    i0 = np.argmax(free)
    u0, v0, t0 = u[i0], res.column("v1_m_s")[i0], t[i0]
    tt = t[free] - t0
    exact = np.exp(-zeta * W * tt) * (u0 * np.cos(wd * tt) + (v0 + zeta * W * u0) / wd * np.sin(wd * tt))
    assert np.max(np.abs(u[free] - exact)) < 2e-3 * np.max(np.abs(u))
    assert res.energy_balance < 2e-3
    e = res.summary()["energy"]
    assert e["viscous_J"] == pytest.approx(e["input_J"] - res.column("E_kinetic_J")[-1] - e["hysteretic_J"], rel=1e-3)
    # the damper columns: rate of deformation along x1 (= v1 through G) and c times it
    np.testing.assert_allclose(res.column("d1_v_m_s"), res.column("v1_m_s"), rtol=0, atol=1e-12)
    c_total = 2 * zeta * math.sqrt(2 * K * MASS)
    np.testing.assert_allclose(res.column("d2_f_N"), c_total / 4 * res.column("d2_v_m_s"))
    assert [c for c in res.columns if c.startswith("d")] == [f"d{k}_{q}" for k in (1, 2, 3) for q in ("v_m_s", "f_N")]


@pytest.mark.parametrize("r", [0.5, 1.0, 2.0])
def test_steady_state_transmissibility_of_a_damped_oscillator(tmp_path, r):
    """Support sine at r times the natural frequency: the steady total acceleration over the input is
    sqrt(1 + (2 zeta r)^2) / sqrt((1 - r^2)^2 + (2 zeta r)^2)."""
    zeta = 0.1
    f = r * W / (2 * math.pi)
    data = damped_square(zeta, {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": f,
                                                   "units": "m/s2"}}})
    data["analysis"] = {"dt": 1.0 / f / 200, "duration": 40 / (zeta * W)}  # transient decayed to e^-40
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    last = res.time > res.time[-1] - 3.0 / f
    t_measured = np.max(np.abs(res.column("at1_m_s2")[last]))
    exact = math.sqrt(1 + (2 * zeta * r) ** 2) / math.sqrt((1 - r * r) ** 2 + (2 * zeta * r) ** 2)
    assert t_measured == pytest.approx(exact, rel=2e-3)


def test_central_difference_with_heavy_damping_is_stable_up_to_omega_dt_2(tmp_path):
    """Damping enters the acceleration solve (M + dt/2 C): stability needs omega dt < 2 whatever the damping."""
    data = damped_square(3.0, {"force": {"p1": {"type": "half-sine", "amplitude": 2000.0, "units": "N",
                                                "duration": 0.05}}})
    data["analysis"] = {"dt": 1.9 / W, "duration": 200 * 1.9 / W, "max_omega_dt": 10.0}
    res = rbhyst.run(write_deck(tmp_path, data), integrator="central-difference", estimate=False)
    u = np.abs(res.column("u1_m"))
    assert np.max(u[-20:]) < 1e-3 * np.max(u)  # decayed, not grown


def test_a_scene_without_dampers_has_no_damper_columns(tmp_path):
    res = rbhyst.run(write_deck(tmp_path, seed_deck(duration=0.2)), estimate=False)
    assert "E_viscous_J" not in res.columns and not any(c.startswith("d1_") for c in res.columns)
    assert "dampers" not in res.summary()


# ------------------------------------------------------------------ gravity


def vrm_static(branch: dict, force: float) -> float:
    """Deformation u of one element loaded from its virgin state to ``force`` along eq. 14
    (no beta, gamma terms): f(u) = c_s(u) - c_s(0) exp(-s alpha u), s the sign of the force."""
    s = 1.0 if force > 0 else -1.0
    kb, f0, alpha = branch["kb"], branch["f0"], branch["alpha"]

    def f(u):
        return kb * u + s * f0 - s * f0 * math.exp(-s * alpha * u)

    return brentq(lambda u: f(u) - force, 0.0, s * 10 * abs(force) / kb)


def hanging_deck(gravity=(0.0, -9.81)) -> dict:
    """A square on two vertical VRM elements under its lower corners and two horizontal ones."""
    sets = {"vert": {"loading": {"kb": 5.0e4, "f0": 300.0, "alpha": 800.0},
                     "unloading": {"kb": 5.0e4, "f0": 300.0, "alpha": 800.0}},
            "hor": linear_set(1.0e5)}
    return {
        "body": {"vertices": [[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]], "mass": 200.0,
                 "gravity": list(gravity)},
        "hysteresis": sets,
        "elements": [{"vertex": 1, "angle_deg": 90.0, "hysteresis": "vert"},
                     {"vertex": 2, "angle_deg": 90.0, "hysteresis": "vert"},
                     {"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "hor"},
                     {"point": [0.0, 1.0], "angle_deg": 0.0, "hysteresis": "hor"}],
        "analysis": {"dt": 1e-3, "duration": 1.0},
    }


def test_the_static_deflection_under_gravity_is_eq_14_solved_by_hand(tmp_path):
    res = rbhyst.run(write_deck(tmp_path, hanging_deck()))
    static = res.summary()["static"]
    # each vertical element carries half the weight; the body sinks by its deformation
    u = vrm_static(hanging_deck()["hysteresis"]["vert"]["loading"], -200.0 * 9.81 / 2)
    assert static["u2_m"] == pytest.approx(u, rel=1e-10)
    assert static["u1_m"] == pytest.approx(0.0, abs=1e-14) and static["theta3_rad"] == pytest.approx(0.0, abs=1e-13)
    assert [e["f_N"] for e in static["elements"][:2]] == pytest.approx([-981.0, -981.0], rel=1e-10)
    assert static["out_of_balance"] < 1e-12


def test_rest_stays_rest_under_gravity(tmp_path):
    res = rbhyst.run(write_deck(tmp_path, hanging_deck()))
    peaks = res.summary()["peaks"]
    assert peaks["u1_m"] == peaks["u2_m"] == peaks["theta3_rad"] == peaks["a2_m_s2"] == 0.0
    # the element columns are total: they hold the static deformation
    assert res.column("e1_u_m")[-1] == pytest.approx(res.summary()["static"]["elements"][0]["u_m"], rel=0, abs=0)


@pytest.mark.parametrize("method", ["chang", "newmark", "adaptive"])
def test_shaking_under_gravity_starts_from_the_static_state(tmp_path, method):
    """Support motion on the preloaded body: the estimate (adaptive from the same static state)
    agrees with the run, and displacements start at zero."""
    data = hanging_deck()
    data["excitation"] = {"support": {"x2": {"type": "sine", "amplitude": 0.3, "frequency_hz": 4.0, "units": "g"}}}
    res = rbhyst.run(write_deck(tmp_path, data), integrator=method)
    assert res.column("u2_m")[0] == 0.0
    assert max(res.accuracy["estimated_error"].values()) < 0.01
    assert res.energy_balance < 2e-3


def test_gravity_the_elements_cannot_carry_exits_3(tmp_path):
    data = hanging_deck(gravity=(0.0, -9.81e6))
    data["body"]["gravity_check"] = False  # (meant: the elements' strength is what is tested)
    data["hysteresis"]["vert"] = {"loading": {"kb": 0.0, "f0": 300.0, "alpha": 800.0},
                                  "unloading": {"kb": 0.0, "f0": 300.0, "alpha": 800.0}}
    with pytest.raises(rbhyst.AnalysisError, match="cannot carry"):
        rbhyst.run(write_deck(tmp_path, data))


# ------------------------------------------------------------------ stroke


def test_stroke_utilization_from_every_step_and_a_warning_beyond(tmp_path):
    data = seed_deck(duration=1.0)
    data["elements"][1]["stroke"] = 0.5e-3  # shear at P1: symmetric
    data["elements"][0]["stroke"] = [-0.05, 0.05]
    data["output"] = {"every": 7}
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    full = rbhyst.run(write_deck(tmp_path, dict(data, output={"every": 1})), estimate=False)
    shear = res.summary()["elements"][1]["stroke"]
    u = full.column("e3_u_m")
    i = int(np.argmax(np.abs(u)))
    assert shear["peak_deformation_m"] == u[i] and shear["time_of_peak_s"] == full.time[i]
    assert shear["utilization"] == pytest.approx(abs(u[i]) / 0.5e-3)
    assert shear["limits_m"] == [-0.5e-3, 0.5e-3]
    axial = res.summary()["elements"][0]["stroke"]
    assert axial["utilization"] < 1
    [w] = [w for w in res.warnings if "stroke" in w]
    assert w.startswith("element e3-e4 ('wri_shear') goes beyond its stroke") and f"t = {full.time[i]:.4g} s" in w


def test_bad_strokes_and_dampers_get_one_line(tmp_path):
    data = seed_deck(duration=0.2)
    data["elements"][0]["stroke"] = [0.01, 0.05]
    data["dampers"] = [{"vertex": 12, "angle_deg": 0.0, "c": 10.0}, {"point": [0, 0], "angle_deg": 0.0, "c": -1.0}]
    with pytest.raises(rbhyst.InputError) as err:
        rbhyst.load_deck(write_deck(tmp_path, data))
    assert err.value.problems == [
        "elements[1].stroke: [0.01, 0.05] must be [lower, upper] with lower < 0 < upper (m)",
        "dampers[2].c: must be greater than or equal to 0",  # (0 is a no-damper baseline)
    ]
    data["elements"][0]["stroke"] = [-0.01, 0.05]
    data["dampers"][1]["c"] = 1.0
    with pytest.raises(rbhyst.InputError) as err:
        rbhyst.load_deck(write_deck(tmp_path, data))
    assert err.value.problems == ["dampers[1].vertex: 12 is out of range: the body has 8 vertices"]
