"""Stiff and extreme scenes: each asserts a number against an exact or a much finer solution."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rbhyst.model.deck import parse_deck
from rbhyst.errors import AnalysisError
from rbhyst.model.system import assemble
from rbhyst.solve.plan import Settings, simulate
from conftest import DECKS, linear_set, seed_deck, square_linear_deck

EXPLICIT = ["chang", "central-difference"]


def system_of(data, tmp_path=DECKS):
    return assemble(parse_deck(data), tmp_path)


def rel_err(res, ref):
    return np.max(np.abs(res.d - ref.d), axis=0) / np.max(np.abs(ref.d), axis=0)


def seed_with_record(duration=5.0, alpha_factor=1.0):
    data = seed_deck(duration=duration)
    data["excitation"] = {"support": {
        "x1": {"file": "records/synthetic_x1.csv", "units": "g"},
        "x2": {"file": "records/synthetic_x2.csv", "units": "g"}}}
    for name in ("wri_axial", "wri_shear"):
        for branch in ("loading", "unloading"):
            data["hysteresis"][name][branch]["alpha"] *= alpha_factor
    return data


@pytest.fixture(scope="module")
def sharp():
    """The seed's isolators with alpha x 100 (nearly sharp yield) and a fine solution."""
    system = system_of(seed_with_record(alpha_factor=100.0))
    fine = simulate(system, Settings(integrator="central-difference", dt=2.5e-6, duration=5.0,
                                     every=400, max_omega_dt=0.1))
    return system, fine


@pytest.mark.parametrize("method", EXPLICIT)
def test_monitor_catches_the_silent_failure_of_sharp_yield(sharp, method):
    system, fine = sharp
    blind = simulate(system, Settings(integrator=method, dt=1e-3, duration=5.0, max_omega_dt=1e9))
    watched = simulate(system, Settings(integrator=method, dt=1e-3, duration=5.0))
    # without the monitor the history is off by far more than tens of percent, and only the
    # energy balance would tell
    assert rel_err(blind, fine).max() > 0.5
    assert blind.energy_balance > 0.1
    # with it, the stiff instants are subdivided and the answer is that of the fine solution
    # (to the spread of fine solutions themselves: 1e-5 and 2.5e-6 s differ by ~3 %)
    assert watched.substeps > 1000
    assert rel_err(watched, fine)[[0, 2]].max() < 0.05
    assert watched.energy_balance < 2e-3


def test_nearly_sharp_corners_alpha_1e6(tmp_path):
    """alpha = 1e6 /m on a bilinear-like set: the linear-elastic-perfectly-plastic limit."""
    data = square_linear_deck(k=1.0e5, mass=100.0)
    branch = {"kb": 1.0e3, "f0": 1.0e3, "alpha": 1.0e6}
    data["hysteresis"]["epp"] = {"loading": branch, "unloading": dict(branch)}
    for el in data["elements"]:
        el["hysteresis"] = "epp"
    # 100 kg at 3 g asks 2940 N of two elements that yield at 1000 N each
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 3.0, "frequency_hz": 2.0,
                                             "units": "g", "cycles": 3}}}
    data["analysis"]["duration"] = 2.0
    system = system_of(data, tmp_path)
    fine = simulate(system, Settings(dt=1e-6, duration=2.0, every=1000, max_omega_dt=0.1))
    res = simulate(system, Settings(dt=1e-3, duration=2.0))
    assert res.substeps > 0
    assert rel_err(res, fine)[0] < 0.02
    # yield force reached: each x1 element carries at most f0 + kb |u|
    u_max = np.max(np.abs(res.element_u[:, 0]))
    assert np.max(np.abs(res.element_f[:, 0])) == pytest.approx(1e3 + 1e3 * u_max, rel=1e-3)


def test_exponential_branch_driven_out_of_range_stops_cleanly(tmp_path):
    data = square_linear_deck(k=1.0e4, mass=100.0)
    data["hysteresis"]["stiffening"] = {
        "loading": {"kb": 1.0e4, "f0": 10.0, "alpha": 100.0, "beta1": 1.0, "beta2": 500.0},
        "unloading": {"kb": 1.0e4, "f0": 10.0, "alpha": 100.0, "beta1": -1.0, "beta2": -500.0}}
    data["elements"][0]["hysteresis"] = "stiffening"
    data["excitation"] = {"force": {"point": [0.0, 0.0], "p1": {
        "type": "sine", "amplitude": 1.0e9, "frequency_hz": 0.5, "units": "N"}}}
    data["analysis"]["duration"] = 1.0
    system = system_of(data, tmp_path)
    with pytest.raises(AnalysisError) as err:
        simulate(system, Settings(dt=1e-3, duration=1.0))
    msg = str(err.value)
    assert "element e1" in msg and "t = " in msg
    # beta2 out of range: said as such, not as a request for an absurdly small step
    assert ("left its calibrated range" in msg) or ("beta2 is out of range" in msg and "e^" in msg)
    assert "a step of" not in msg


def test_stiffness_ratio_1e4_between_reversal_and_branch(tmp_path):
    """k_a / kb = 1e4: the stiff instant after each reversal is resolved by substeps."""
    data = square_linear_deck(k=1.0e5, mass=200.0)
    branch = {"kb": 200.0, "f0": 500.0, "alpha": 2000.0}  # k_a = 200 + 2000 * 1000
    data["hysteresis"]["h"] = {"loading": branch, "unloading": dict(branch)}
    for el in data["elements"]:
        el["hysteresis"] = "h"
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.6, "frequency_hz": 1.5,
                                             "units": "g", "phase_deg": 90.0}}}
    data["analysis"]["duration"] = 3.0
    system = system_of(data, tmp_path)
    assert system.k_reversal[0] / system.k0[0] == pytest.approx(10001.0, rel=1e-12)
    fine = simulate(system, Settings(dt=2e-6, duration=3.0, every=1000))
    for method in EXPLICIT:
        res = simulate(system, Settings(integrator=method, dt=2e-3, duration=3.0))
        assert rel_err(res, fine)[0] < 0.01, method


def _sine_response(w, big_w, force, t):
    """x'' + w^2 x = F sin(W t) from rest: F / (w^2 - W^2) (sin W t - (W / w) sin w t)."""
    return force / (w * w - big_w * big_w) * (np.sin(big_w * t) - big_w / w * np.sin(w * t))


def _budget(w, big_w):
    """Error allowed against _sine_response: 0.1 % on the forced part, plus the free part's
    whole swing 2 W / w, since over hundreds of periods at omega h <= 0.5 (period error up to
    2 %) the free vibration may be entirely out of phase: nothing a user reads depends on it."""
    return 1e-3 + 2.2 * big_w / w


def test_one_gram_body_on_stiff_elements(tmp_path):
    """omega = sqrt(2k / 1 g) = 2e4 rad/s: omega dt = 20 at dt = 1 ms, resolved by substeps."""
    k, mass = 2.0e5, 1.0e-3
    data = square_linear_deck(k=k, mass=mass)
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 5.0,
                                             "units": "m/s2"}}}
    data["analysis"]["duration"] = 0.2
    system = system_of(data, tmp_path)
    res = simulate(system, Settings(dt=1e-3, duration=0.2))
    assert res.substeps >= 200 * 32 and res.max_omega_dt <= 0.5
    w, big_w = math.sqrt(2 * k / mass), 2 * math.pi * 5.0
    exact = _sine_response(w, big_w, -1.0, res.time)
    assert np.max(np.abs(res.d[:, 0] - exact)) < _budget(w, big_w) * np.max(np.abs(exact))


def test_excitation_far_above_the_body_frequencies(tmp_path):
    """A 200 Hz shake of a 4.5 Hz body: the body barely moves, the isolation is nearly total."""
    k, mass = 2.0e5, 500.0
    data = square_linear_deck(k=k, mass=mass)
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 5.0, "frequency_hz": 200.0,
                                             "units": "m/s2"}}}
    data["analysis"]["duration"] = 0.5
    system = system_of(data, tmp_path)
    for method in EXPLICIT:
        res = simulate(system, Settings(integrator=method, dt=1e-4, duration=0.5))
        w, big_w = math.sqrt(2 * k / mass), 2 * math.pi * 200.0
        exact = _sine_response(w, big_w, -5.0, res.time)
        # 4 % of the period per step: the 200 Hz forced part is what the body does
        assert np.max(np.abs(res.d[:, 0] - exact)) < 0.01 * np.max(np.abs(exact)), method
        assert np.max(np.abs(res.d[:, 0])) == pytest.approx(5.0 / (big_w**2 - w * w) * (1 + big_w / w),
                                                            rel=0.02)


def test_a_scene_at_rest_stays_exactly_at_rest(tmp_path):
    data = seed_deck(duration=2.0)
    del data["excitation"]
    system = system_of(data, tmp_path)
    for method in EXPLICIT:
        res = simulate(system, Settings(integrator=method, dt=1e-3, duration=2.0))
        table = res.table
        assert not np.any(table[:, 1:]), method


def test_a_million_steps_with_decimated_output(tmp_path):
    data = seed_deck(duration=100.0)
    data["analysis"]["dt"] = 1e-4
    system = system_of(data, tmp_path)
    res = simulate(system, Settings(dt=1e-4, duration=100.0, every=1000))
    assert res.steps == 1_000_000
    assert res.d.shape == (1001, 3) and res.element_u.shape == (1001, 8)
    np.testing.assert_allclose(res.time[-1], 100.0)
    assert res.energy_balance < 1e-4
    assert np.all(np.isfinite(res.d))


def test_long_thin_polygon_with_a_tiny_inertia(tmp_path):
    """A 2 m x 2 mm bar of 0.1 kg: J = m (L^2 + t^2) / 12 = 0.033 kg m2 on end springs."""
    length, thick, mass, k = 2.0, 0.002, 0.1, 1.0e5
    data = {
        "body": {"vertices": [[-1, -0.001], [1, -0.001], [1, 0.001], [-1, 0.001]], "mass": mass},
        "hysteresis": {"lin": linear_set(k)},
        "elements": [
            {"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "lin"},
            {"vertex": 2, "angle_deg": 90.0, "hysteresis": "lin"},
            {"vertex": 4, "angle_deg": 90.0, "hysteresis": "lin"},
        ],
        "excitation": {"force": {"m3": {"type": "sine", "amplitude": 1.0, "frequency_hz": 2.0,
                                        "units": "N m"}}},
        "analysis": {"dt": 1e-3, "duration": 0.5},
    }
    system = system_of(data, tmp_path)
    j = mass * (length**2 + thick**2) / 12
    assert system.mass[2] == pytest.approx(j, rel=1e-12)
    res = simulate(system, Settings(dt=1e-3, duration=0.5))
    assert res.substeps > 0
    # K33 = 2 k (1 m)^2 + 2 k (1 mm)^2 (the end springs sit at the bar's corners)
    k33 = 2 * k * (1.0 + 0.001**2)
    w, big_w = math.sqrt(k33 / j), 4 * math.pi
    exact = _sine_response(w, big_w, 1.0 / j, res.time)
    assert np.max(np.abs(res.d[:, 2] - exact)) < _budget(w, big_w) * np.max(np.abs(exact))


def test_elements_far_from_the_body(tmp_path):
    """Elements 25 m from G on a 1 m body: the rotational stiffness grows with the lever arm squared."""
    k, mass = 2.0e5, 500.0
    data = square_linear_deck(k=k, mass=mass)
    for el in data["elements"]:
        el["point"] = [50.0 * x for x in el["point"]]
    data["excitation"] = {"force": {"m3": {"type": "sine", "amplitude": 1.0e4, "frequency_hz": 1.0,
                                           "units": "N m"}}}
    system = system_of(data, tmp_path)
    res = simulate(system, Settings(dt=1e-3, duration=1.0))
    k33, jj = 4 * k * 25.0**2, mass / 6
    w, big_w = math.sqrt(k33 / jj), 2 * math.pi
    exact = _sine_response(w, big_w, 1.0e4 / jj, res.time)
    assert res.substeps > 0
    assert np.max(np.abs(res.d[:, 2] - exact)) < _budget(w, big_w) * np.max(np.abs(exact))
