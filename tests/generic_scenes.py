"""The solve core takes the number of coordinates from the System: bodies of one and two
coordinates, built by hand, run through the same kernels as the plane body and match their
closed-form responses.

Run by tests/test_generic.py with NUMBA_DISABLE_JIT=1 (the kernels' own code, uncompiled); on its
own: ``NUMBA_DISABLE_JIT=1 pytest tests/generic_scenes.py``."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rbhyst.model.body import Body
from rbhyst.model.coordinates import rotation, translation
from rbhyst.model.hysteresis import parameter_set
from rbhyst.model.settings import Settings
from rbhyst.model.signals import sine
from rbhyst.model.system import Element, Excitation, System, load_directions
from rbhyst.solve.plan import simulate

M = 250.0  # kg
K = M * (2 * math.pi * 1.5) ** 2  # N/m: 1.5 Hz on one spring
FIXED_STEP = ("chang", "central-difference", "newmark", "kr-alpha")


def spring(k: float) -> np.ndarray:
    """A linear spring as a VRM set: equal limiting curves kb u, no f0 (docs/reference/deck.md, Hysteresis sets)."""
    branch = {"kb": k, "alpha": 100.0}
    return parameter_set(branch, branch)


def system(coordinates, mass, rows, k, excitation, points=()) -> System:
    """A body on linear springs, one kernel row each (b = rows[e]), as assemble would give it."""
    rows = np.asarray(rows, dtype=float)
    square = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    body = Body("direct", float(mass[0]), np.zeros(2), 1.0, (), square, 1.0)
    return System(
        title="by hand", body=body, mass=np.asarray(mass, dtype=float), bvec=rows, mult=np.ones(len(rows)),
        params=np.array([spring(ke) for ke in k]), k0=np.asarray(k, dtype=float), k_reversal=np.asarray(k, dtype=float),
        elements=tuple(Element((0.0, 0.0), 0.0, "spring", 1, e) for e in range(len(rows))),
        excitation=excitation, coordinates=tuple(coordinates),
    )


def settings(integrator: str, dt: float = 1e-3, duration: float = 3.0) -> Settings:
    return dataclasses.replace(Settings(), integrator=integrator, dt=dt, duration=duration, estimate=False)


def one_dof(excitation_keys: dict, constant=None) -> System:
    """A body moving along x1 only, q = (u1,), on one spring along x1."""
    coords = (translation(1),)
    ex = Excitation(directions=load_directions(coords), constant=constant, **excitation_keys)
    return system(coords, [M], [[1.0]], [K], ex)


def test_a_one_coordinate_body_has_its_own_columns():
    res = simulate(one_dof({}, constant=(100.0,)), settings("chang", duration=0.1))
    assert res.columns[:5] == ("time_s", "u1_m", "v1_m_s", "a1_m_s2", "at1_m_s2")
    assert res.d.shape == (101, 1)
    assert "R1_N" in res.columns and "theta3_rad" not in res.columns


@pytest.mark.parametrize("integrator", FIXED_STEP + ("adaptive",))
def test_one_coordinate_step_load_is_the_closed_form(integrator):
    """A constant force F from rest: u = F / k (1 - cos omega t), every method within its order."""
    force = 100.0
    res = simulate(one_dof({}, constant=(force,)), settings(integrator))
    w = math.sqrt(K / M)
    exact = force / K * (1.0 - np.cos(w * res.time))
    err = np.max(np.abs(res.d[:, 0] - exact)) / np.max(np.abs(exact))
    assert err < (1e-6 if integrator == "adaptive" else 2e-4), err
    # the energy balance closes: the force's work is the spring's and the kinetic energy
    assert np.max(np.abs(res.energy_error)) < (1e-6 if integrator == "adaptive" else 1e-4) * force * force / K


@pytest.mark.parametrize("integrator", FIXED_STEP + ("adaptive",))
def test_one_coordinate_harmonic_support_motion_is_the_closed_form(integrator):
    """ag = A sin(W t) from rest, undamped: m u'' + k u = -m ag gives
    u = -A / (w^2 - W^2) (sin W t - W / w sin w t), and the total acceleration at = u'' + ag."""
    amp, f = 2.0, 0.8
    res = simulate(one_dof({"ag1": sine(amp, f)}), settings(integrator))
    w, big_w = math.sqrt(K / M), 2 * math.pi * f
    t = res.time
    exact = -amp / (w * w - big_w * big_w) * (np.sin(big_w * t) - big_w / w * np.sin(w * t))
    at = -w * w * exact  # m at = -k u: the spring alone acts on the body
    tol = 1e-6 if integrator == "adaptive" else 1e-3
    assert np.max(np.abs(res.d[:, 0] - exact)) < tol * np.max(np.abs(exact))
    assert np.max(np.abs(res.column("at1_m_s2") - at)) < tol * np.max(np.abs(at))
    assert np.array_equal(res.column("ag1_m_s2"), amp * np.sin(big_w * t))


def test_one_coordinate_chang_converges_at_second_order():
    force = 100.0
    errors = []
    for dt in (4e-3, 2e-3, 1e-3):
        res = simulate(one_dof({}, constant=(force,)), settings("chang", dt=dt))
        exact = force / K * (1.0 - np.cos(math.sqrt(K / M) * res.time))
        errors.append(np.max(np.abs(res.d[:, 0] - exact)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.1), orders


def two_dof(force_point, **signals) -> tuple[System, np.ndarray]:
    """A body that slides along x1 and rocks about x3, q = (u1, theta3), on two springs along x1
    at heights 0.4 m and -0.7 m (b = (1, -x2)), forces at ``force_point``; with its stiffness."""
    coords = (translation(1), rotation(3))
    heights = np.array([0.4, -0.7])
    rows = np.column_stack([np.ones(2), -heights])
    k = np.array([K, 2.0 * K])
    ex = Excitation(point=force_point, directions=load_directions(coords, force_point), **signals)
    return system(coords, [M, 40.0], rows, k, ex), (rows.T * k) @ rows


@pytest.mark.parametrize("integrator", FIXED_STEP + ("adaptive",))
def test_two_coordinate_harmonic_force_is_the_modal_closed_form(integrator):
    """p1 = P sin(W t) at x_P: p = T(x_P)^T (1) P sin(W t) = (1, -x2P) P sin(W t) (eq. 13), and
    from rest q = sum_i phi_i phi_i^T p0 / (w_i^2 - W^2) (sin W t - W / w_i sin w_i t) over the
    mass-normalized modes."""
    amp, f, point = 150.0, 0.9, (0.2, 0.5)
    sys2, stiffness = two_dof(point, p1=sine(amp, f))
    p0 = amp * np.array(sys2.excitation.directions["p1"])
    assert sys2.excitation.directions["p1"] == (1.0, -0.5)
    res = simulate(sys2, settings(integrator))
    m_half = 1.0 / np.sqrt(sys2.mass)
    w2, vec = np.linalg.eigh(stiffness * np.outer(m_half, m_half))
    phi = vec * m_half[:, None]
    w, big_w, t = np.sqrt(w2), 2 * math.pi * f, res.time[:, None]
    eta = (phi.T @ p0) / (w2 - big_w ** 2) * (np.sin(big_w * t) - big_w / w * np.sin(w * t))
    exact = eta @ phi.T
    tol = 1e-6 if integrator == "adaptive" else 2e-3
    for c in range(2):
        assert np.max(np.abs(res.d[:, c] - exact[:, c])) < tol * np.max(np.abs(exact[:, c])), (integrator, c)
    assert res.columns[1:3] == ("u1_m", "theta3_rad")


def test_a_point_of_a_two_coordinate_body_moves_by_its_kinematics():
    """u_P1 = u1 - theta3 x2 (eqs. 7-8 with q = (u1, theta3)); the point has no u2."""
    sys2, _ = two_dof((0.0, 0.3), p1=sine(100.0, 2.0))
    res = simulate(sys2, dataclasses.replace(settings("chang", duration=0.5), points=(("top", (0.2, 0.5)),)))
    assert [c for c in res.columns if c.startswith("top_")] == ["top_u1_m", "top_at1_m_s2"]
    np.testing.assert_array_equal(res.column("top_u1_m"), res.d[:, 0] + res.d[:, 1] * -0.5)


def test_a_one_coordinate_run_estimates_its_error_and_summarizes_itself():
    """The results layer needs no plane either: the error estimate covers the body's own
    columns, and the summary its own peaks."""
    from rbhyst.results.analysis import analyse

    res = analyse(one_dof({"ag1": sine(2.0, 0.8)}), dataclasses.replace(settings("chang"), estimate=True))
    error = res.accuracy["estimated_error"]
    assert set(error) == {"u1", "at1", "R1", "e1_f"}
    assert max(error.values()) < 1e-3 and res.warnings == []
    assert set(res.summary()["peaks"]) >= {"u1_m", "at1_m_s2", "ag1_m_s2", "R1_N", "e1_f_N"}
