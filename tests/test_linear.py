"""A linear scene against its exact solution, and the observed order of the loop integrators."""

import math

import numpy as np
import pytest

from rbhyst.model.deck import parse_deck
from rbhyst.model.system import assemble
from rbhyst.solve.plan import Settings, simulate
from conftest import square_linear_deck

K, MASS, SIDE = 2.0e5, 500.0, 1.0
A_G, F_HZ = 2.0, 2.5  # support acceleration amplitude (m/s2) and frequency


def scene(tmp_path, phase_deg=90.0):
    deck = square_linear_deck(K, MASS, SIDE)
    deck["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": A_G, "frequency_hz": F_HZ,
                                             "units": "m/s2", "phase_deg": phase_deg}}}
    return assemble(parse_deck(deck), tmp_path)


def exact_u1(t):
    """u'' + w^2 u = -A cos(W t) from rest: u = -A/(w^2 - W^2) (cos W t - cos w t)."""
    w = math.sqrt(2 * K / MASS)
    big_w = 2 * math.pi * F_HZ
    return -A_G / (w * w - big_w * big_w) * (np.cos(big_w * t) - np.cos(w * t))


@pytest.mark.parametrize("method", ["chang", "central-difference"])
def test_linear_scene_matches_the_exact_solution(tmp_path, method):
    system = scene(tmp_path)
    res = simulate(system, Settings(integrator=method, dt=2.5e-4, duration=2.0))
    ref = exact_u1(res.time)
    err = np.max(np.abs(res.d[:, 0] - ref)) / np.max(np.abs(ref))
    assert err < 2e-3
    # nothing excites x2 or the rotation of a decoupled body
    assert np.max(np.abs(res.d[:, 1:])) < 1e-12 * np.max(np.abs(res.d[:, 0]))
    # a linear spring stores what it is given: the energy balance closes to the method's accuracy
    assert res.energy_balance < 1e-3


@pytest.mark.parametrize("method", ["chang", "central-difference"])
def test_observed_order_is_two_with_a_record_that_starts_at_its_peak(tmp_path, method):
    system = scene(tmp_path)  # cos: the excitation starts at its peak, a0 = -A != 0
    dts = [4e-3, 2e-3, 1e-3, 5e-4]
    errs = []
    for dt in dts:
        res = simulate(system, Settings(integrator=method, dt=dt, duration=2.0))
        errs.append(np.max(np.abs(res.d[:, 0] - exact_u1(res.time))))
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert slope == pytest.approx(2.0, abs=0.2)


def test_zero_initial_acceleration_would_cost_an_order(tmp_path):
    """Guard for the equilibrium start: it is what keeps the order above at 2."""
    system = scene(tmp_path)
    res = simulate(system, Settings(dt=1e-3, duration=0.01))
    assert res.a[0, 0] == pytest.approx(-A_G)
    assert res.total_acceleration[0, 0] == pytest.approx(0.0, abs=1e-12)


def test_first_steps_of_chang_and_central_difference_by_hand(tmp_path):
    """d1 = dt^2 B2 a0 with B2 = (M + dt^2/4 K0)^-1 M / 2 (Chang) or 1/2 (central difference)."""
    system = scene(tmp_path)
    dt = 1e-2
    w2 = 2 * K / MASS
    a0 = -A_G
    chang = simulate(system, Settings(dt=dt, duration=dt))
    assert chang.d[1, 0] == pytest.approx(0.5 * dt * dt * a0 / (1 + w2 * dt * dt / 4), rel=1e-12)
    cd = simulate(system, Settings(integrator="central-difference", dt=dt, duration=dt))
    assert cd.d[1, 0] == pytest.approx(0.5 * dt * dt * a0, rel=1e-12)
    p1 = -A_G * math.cos(2 * math.pi * F_HZ * dt)
    assert cd.a[1, 0] == pytest.approx(p1 - w2 * cd.d[1, 0], rel=1e-12)
