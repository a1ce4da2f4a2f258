"""Exact kinematics of a body in space (analysis.kinematics = "exact" in 3-D) against an independent
integration of the Newton-Euler equations written here from forces and moments, with a unit
quaternion for the attitude and the full inertia tensor (not the rotation vector, the rows or
the principal axes the kernels use); every method's order; the plane's exact run reproduced by
a prism; small against exact on small motions; rest under gravity."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from conftest import linear_set
from rbhyst.model.deck import parse_deck
from rbhyst.model.settings import settings_from_deck
from rbhyst.model.system import assemble
from rbhyst.solve.plan import simulate

K, MASS = 2.0e4, 300.0  # N/m each spring, kg
SIZE = (1.0, 0.6, 0.4)  # the box, m: three different principal moments, so Euler's term acts
A, B, H = (s / 2 for s in SIZE)
#: the springs: point from G and line of action; at corners and off their lines, so that every
#: row turns with the body and the six motions are restrained
SPRINGS = (((A, B, -H), (1.0, 0.0, 0.0)), ((-A, -B, -H), (1.0, 0.0, 0.0)),
           ((A, -B, -H), (0.0, 1.0, 0.0)), ((-A, B, -H), (0.0, 1.0, 0.0)),
           ((A, B, -H), (0.0, 0.0, 1.0)), ((-A, B, -H), (0.0, 0.0, 1.0)),
           ((A, -B, -H), (0.0, 0.0, 1.0)), ((-A, -B, -H), (0.0, 0.0, 1.0)),
           ((A, 0.0, H), (0.6, 0.0, 0.8)))
T_PULSE = 0.3
MOMENTS = {"m1": 1400.0, "m2": -2200.0, "m3": 3300.0}  # N m, half-sine peaks
FORCE, FORCE_AT = 800.0, (A, -B, H)  # p2 (N) at a top corner: its arm turns with the body
FIXED_STEP = ("chang", "central-difference", "newmark", "kr-alpha")
ADAPTIVE = {"integrator": "adaptive", "rtol": 1e-11}


def box_inertia() -> np.ndarray:
    a, b, c = SIZE
    return MASS / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def deck(kinematics: str, scale: float = 1.0, duration: float = 1.2, dt: float = 1e-3, turn=None) -> dict:
    """The box on its springs under moment pulses and a force at a corner; ``turn``: a rotation
    (scipy) of the whole scene, so that its inertia tensor is not diagonal in the deck's axes."""
    rot = turn if turn is not None else Rotation.identity()
    pulse = {"type": "half-sine", "duration": T_PULSE}
    corners = np.array([[sx * A, sy * B, sz * H] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    force = {k: dict(pulse, units="N m", amplitude=scale * v) for k, v in zip(("m1", "m2", "m3"),
                                                                           rot.apply(list(MOMENTS.values())))}
    for k, v in zip(("p1", "p2", "p3"), rot.apply([0.0, scale * FORCE, 0.0])):
        force[k] = dict(pulse, units="N", amplitude=float(v))
    force["point"] = [float(x) for x in rot.apply(FORCE_AT)]
    j = rot.as_matrix() @ box_inertia() @ rot.as_matrix().T
    return {
        "body": {"mass": MASS, "mass_centre": [0.0, 0.0, 0.0], "inertia": j.tolist(),
                 "vertices": rot.apply(corners).tolist()},
        "hysteresis": {"lin": linear_set(K)},
        "elements": [{"point": rot.apply(x).tolist(), "direction": rot.apply(d).tolist(), "hysteresis": "lin"}
                     for x, d in SPRINGS],
        "excitation": {"force": force},
        "analysis": {"dt": dt, "duration": duration, "kinematics": kinematics},
        "output": {"points": [{"name": "top", "point": rot.apply([A, B, H]).tolist()}]},
    }


def scene(data, tmp_path):
    d = parse_deck(data)
    return assemble(d, tmp_path), dataclasses.replace(settings_from_deck(d), estimate=False)


def run(scene_, **overrides):
    system, settings = scene_
    return simulate(system, dataclasses.replace(settings, **overrides))


def newton_euler(t, y, scale, dampers=()):
    """d/dt (x, quaternion (scalar last), v, omega_body): each spring along its fixed direction d
    pulls at its body point x + R r with -k (d . u_P) d, moment (R r) x F about G; the pulses'
    moments and the force at its turned point; J omega' = R^T M - omega x J omega."""
    x, qt, v, w = y[:3], y[3:7], y[7:10], y[10:13]
    r = Rotation.from_quat(qt / np.linalg.norm(qt)).as_matrix()
    s = scale * math.sin(math.pi * t / T_PULSE) if t < T_PULSE else 0.0
    force = np.array([0.0, s * FORCE, 0.0])
    moment = s * np.array(list(MOMENTS.values())) + np.cross(r @ FORCE_AT, force)
    for p, d in SPRINGS:
        d = np.asarray(d)
        rp = r @ np.asarray(p)
        f = -K * float(d @ (x + rp - p)) * d
        force = force + f
        moment = moment + np.cross(rp, f)
    for p, d, c in dampers:  # along its fixed line, on its turned point's velocity
        d = np.asarray(d)
        rp = r @ np.asarray(p)
        f = -c * float(d @ (v + np.cross(r @ w, rp))) * d
        force = force + f
        moment = moment + np.cross(rp, f)
    j = box_inertia()
    dw = np.linalg.solve(j, r.T @ moment - np.cross(w, j @ w))
    x0, x1, x2, x3 = qt  # q' = q (0, omega) / 2, scalar last
    dq = 0.5 * np.array([x3 * w[0] + x1 * w[2] - x2 * w[1], x3 * w[1] + x2 * w[0] - x0 * w[2],
                         x3 * w[2] + x0 * w[1] - x1 * w[0], -(x0 * w[0] + x1 * w[1] + x2 * w[2])])
    return np.concatenate([v, dq, force / MASS, dw])


def independent(t_out: np.ndarray, scale: float = 1.0, dampers=()):
    """(x (k, 3), attitudes (scipy Rotation), omega in the ground's axes (k, 3)) at t_out."""
    y0 = np.zeros(13)
    y0[6] = 1.0
    sol = solve_ivp(newton_euler, (0.0, t_out[-1]), y0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t_out,
                    max_step=0.01, args=(scale, dampers))
    assert sol.success
    att = Rotation.from_quat(sol.y[3:7].T / np.linalg.norm(sol.y[3:7].T, axis=1)[:, None])
    return sol.y[:3].T, att, att.apply(sol.y[10:13].T)


def rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module")
def large(tmp_path_factory):
    return scene(deck("exact"), tmp_path_factory.mktemp("r3"))


@pytest.fixture(scope="module")
def truth(large):
    res = run(large, **ADAPTIVE)
    return res, independent(res.time)


def test_the_scene_turns_well_beyond_the_small_angles_about_every_axis(truth):
    res, _ = truth
    peaks = np.max(np.abs(res.d[:, 3:]), axis=0)
    assert np.all(peaks > 0.1) and np.max(peaks) > 0.3, peaks


def test_exact_rotations_in_space_agree_with_an_independent_newton_euler_integration(truth):
    res, (x, att, omega) = truth
    assert rel(res.d[:, :3], x) < 1e-6
    assert rel(res.d[:, 3:], att.as_rotvec()) < 1e-6  # theta: the rotation vector
    assert rel(res.v[:, 3:], omega) < 1e-6  # omega in the ground's axes
    top = x + att.apply([A, B, H]) - np.array([A, B, H])
    got = np.column_stack([res.column(f"top_u{k}_m") for k in (1, 2, 3)])
    assert rel(got, top) < 1e-6


def test_the_total_accelerations_are_the_newton_euler_ones(truth):
    """at from the run's rows against the derivative of the independent velocities."""
    res, (x, att, omega) = truth
    t = res.time
    dv = np.array([newton_euler(tk, np.concatenate([xk, ak.as_quat(), vk, ak.inv().apply(wk)]), 1.0)
                   for tk, xk, ak, vk, wk in zip(t[::25], x[::25], att[::25], res.v[::25, :3], omega[::25])])
    at = np.column_stack([res.column(f"at{k}_m_s2") for k in (1, 2, 3)])[::25]
    assert rel(at, dv[:, 7:10]) < 1e-6
    alpha = att[::25].apply(dv[:, 10:13])  # R omega_body' = the ground's d omega / dt
    got = np.column_stack([res.column(f"alphat{k}_rad_s2") for k in (1, 2, 3)])[::25]
    assert rel(got, alpha) < 1e-6


def test_a_turned_scene_runs_in_its_principal_axes_and_agrees(tmp_path):
    turn = Rotation.from_euler("xyz", [0.4, -0.3, 0.7])
    sc = scene(deck("exact", turn=turn, duration=0.8), tmp_path)
    assert sc[0].frame is not None  # its inertia is not diagonal in the deck's axes
    res = run(sc, **ADAPTIVE)
    x, att, omega = independent(res.time)
    assert rel(res.d[:, :3], turn.apply(x)) < 1e-6
    # the attitude seen in the turned axes: turn R turn^T
    assert rel(res.d[:, 3:], turn.apply(att.as_rotvec())) < 1e-6
    assert rel(res.v[:, 3:], turn.apply(omega)) < 1e-6


@pytest.mark.parametrize("integrator", FIXED_STEP)
def test_every_fixed_step_method_converges_at_its_order_in_space(large, truth, integrator):
    errs = []
    dts = (2e-3, 1e-3, 5e-4)
    _, (_, att, _) = truth
    for dt in dts:
        res = run(large, integrator=integrator, dt=dt)
        ref = att.as_rotvec()[::round(dt / 1e-3)] if dt >= 1e-3 else None
        if ref is None:  # rows finer than the reference's: integrate again at them
            _, a2, _ = independent(res.time)
            ref = a2.as_rotvec()
        errs.append(rel(res.d[:, 3:], ref))
    assert errs[-1] < 2e-3
    order = math.log(errs[0] / errs[-1]) / math.log(dts[0] / dts[-1])
    assert order == pytest.approx(2.0, abs=0.25), errs
    assert res.energy_balance < 1e-3


def test_the_adaptive_energy_balance_closes_with_the_gyroscopic_term(truth):
    res, _ = truth
    assert res.energy_balance < 1e-7


def prism(kinematics: str) -> tuple[dict, dict]:
    """The plane test scene of test_kinematics (a square on five springs in its plane, a moment
    and a force) and the same square as a prism in space, held out of the plane by four
    vertical springs at its corners in the plane of G."""
    from test_kinematics import C, FORCE, MOMENT, deck as plane_deck, SPRINGS as PLANE

    plane = plane_deck(kinematics, moment=MOMENT, force=FORCE, duration=1.0)
    depth = 0.6
    sq = [[-C, -C], [C, -C], [C, C], [-C, C]]
    j2 = plane_deck(kinematics, 0.0)["body"]["mass"] * (2 * C) ** 2 / 6.0  # the square's J about x3
    m = plane["body"]["mass"]
    space = {
        "body": {"mass": m, "mass_centre": [0.0, 0.0, 0.0],
                 "inertia": [[m * (4 * C * C + depth ** 2) / 12, 0, 0], [0, m * (4 * C * C + depth ** 2) / 12, 0],
                             [0, 0, j2]],
                 "vertices": [p + [z] for z in (-depth / 2, depth / 2) for p in sq]},
        "hysteresis": plane["hysteresis"],
        "elements": [{"point": [x[0], x[1], 0.0], "direction": [math.cos(math.radians(a)), math.sin(math.radians(a)),
                                                                  0.0], "hysteresis": "lin"} for x, a in PLANE]
        + [{"point": p + [0.0], "direction": [0.0, 0.0, 1.0], "hysteresis": "lin"} for p in sq],
        "excitation": {"force": {**plane["excitation"]["force"], "point": [0.0, 0.0, 0.0]}},
        "analysis": plane["analysis"],
        "output": {"points": [{"name": "corner", "point": [C, C, 0.0]}]},
    }
    return plane, space


@pytest.mark.parametrize("integrator", ["chang", "newmark", "adaptive"])
def test_a_prism_reproduces_the_plane_body_with_exact_kinematics(tmp_path, integrator):
    plane, space = prism("exact")
    over = ADAPTIVE if integrator == "adaptive" else {"integrator": integrator}
    r2 = run(scene(plane, tmp_path), **over)
    r3 = run(scene(space, tmp_path), **over)
    assert np.max(np.abs(r2.d[:, 2])) > 0.2  # it turns by more than the small angles allow
    for k2, k3 in (("u1_m", "u1_m"), ("u2_m", "u2_m"), ("theta3_rad", "theta3_rad"), ("omega3_rad_s", "omega3_rad_s"),
                   ("alphat3_rad_s2", "alphat3_rad_s2"), ("corner_u1_m", "corner_u1_m"),
                   ("corner_at2_m_s2", "corner_at2_m_s2"), ("R3_Nm", "R6_Nm")):
        assert rel(r3.column(k3), r2.column(k2)) < 1e-9, k2
    for k in ("u3_m", "theta1_rad", "theta2_rad"):
        assert np.max(np.abs(r3.column(k))) < 1e-12


def test_small_and_exact_agree_to_second_order_in_the_rotation_in_space(tmp_path):
    diffs = []
    for scale in (0.02, 0.01):
        small = run(scene(deck("small", scale=scale), tmp_path), integrator="chang")
        exact = run(scene(deck("exact", scale=scale), tmp_path), integrator="chang")
        diffs.append(rel(small.d[:, 3:], exact.d[:, 3:]))
    assert diffs[0] / diffs[1] == pytest.approx(2.0, rel=0.05)  # relative: O(theta) of theta


def test_rest_under_gravity_stays_rest_with_exact_rotations(tmp_path):
    data = deck("exact", scale=0.0)
    data["body"]["gravity"] = [0.0, 0.0, -9.81]
    data["body"]["mass_centre"] = [0.05, -0.03, 0.0]  # off centre: the springs' equilibrium turns
    data["excitation"] = {"force": {"p1": {"type": "half-sine", "units": "N", "duration": 0.1, "amplitude": 0.0}}}
    system, settings = scene(data, tmp_path)
    res = simulate(system, dataclasses.replace(settings, integrator="chang"))
    assert np.max(np.abs(res.d)) < 1e-12 and np.max(np.abs(res.v)) < 1e-12


def test_a_small_rotation_run_in_space_reports_its_difference_from_exact(tmp_path):
    """summary's ``kinematics`` of the box turned 0.2-0.5 rad with small rotations: the exact twin's
    difference per column (the same numbers as an exact run of its own), and a warning."""
    from rbhyst.results.analysis import analyse

    system, settings = scene(deck("small"), tmp_path)
    res = analyse(system, dataclasses.replace(settings, integrator="chang"), keep=True)
    kin = res.kinematics
    assert kin["model"] == "small" and kin["neglected"]["share"] > 0.01
    exact = run(scene(deck("exact"), tmp_path), integrator="chang")
    want = rel(res.column("u2_m"), exact.column("u2_m"))
    assert kin["difference"]["u2"] == pytest.approx(want, rel=1e-6)
    assert kin["worst"]["difference"] > 0.05
    said = [w for w in res.warnings if "small rotations" in w]
    assert len(said) == 1 and 'analysis.kinematics = "exact"' in said[0]


def test_a_barely_turning_run_in_space_pays_nothing_and_says_why(tmp_path):
    from rbhyst.results.analysis import analyse

    system, settings = scene(deck("small", scale=1e-4), tmp_path)
    res = analyse(system, settings, keep=True)
    kin = res.kinematics
    assert kin["difference"] is None and kin["neglected"]["share"] < 1e-3 and "not computed" in kin["method"]
    assert not [w for w in res.warnings if "rotation" in w]


def test_the_modes_at_rest_feel_the_weight_with_exact_rotations_in_space(tmp_path):
    """The box on four vertical springs at its base corners and horizontal ones at G's level,
    under gravity along -x3: with exact rotations the rocking stiffnesses at rest are
    k_v sum y^2 - W h and k_v sum x^2 - W h (P-Delta, h from the springs up to G), torsion
    untouched; the seed's rows lack the W h."""
    from rbhyst.solve.modes import tangent_at_rest

    kv, kh = 2.0e5, 1.0e5
    base = [[sx * A, sy * B, -H] for sx in (-1, 1) for sy in (-1, 1)]
    data = deck("small", scale=0.0)
    data["body"]["gravity"] = [0.0, 0.0, -9.81]
    data["hysteresis"] = {"v": linear_set(kv), "h": linear_set(kh)}
    data["elements"] = ([{"point": p, "direction": [0, 0, 1], "hysteresis": "v"} for p in base]
                        + [{"point": [A, 0, 0], "direction": [0, 1, 0], "hysteresis": "h"},
                           {"point": [-A, 0, 0], "direction": [0, 1, 0], "hysteresis": "h"},
                           {"point": [0, B, 0], "direction": [1, 0, 0], "hysteresis": "h"}])
    weight = MASS * 9.81
    for kin, geo in (("small", 0.0), ("exact", weight * H)):
        data["analysis"]["kinematics"] = kin
        system, _ = scene(data, tmp_path)
        k = tangent_at_rest(system)
        assert k[3, 3] == pytest.approx(4 * kv * B * B - geo, rel=1e-9), kin
        assert k[4, 4] == pytest.approx(4 * kv * A * A - geo, rel=1e-9), kin
        assert k[5, 5] == pytest.approx(2 * kh * A * A + kh * B * B, rel=1e-9), kin


#: dampers at corners, off their lines: point, direction, c (N s/m)
DAMPERS = (((A, -B, -H), (1.0, 0.0, 0.0), 600.0), ((-A, B, H), (0.0, 0.6, 0.8), 900.0))


#: the output step of which every damped run's is a multiple (the runs' rows are its rows)
FINEST = 5e-4


@pytest.fixture(scope="module")
def damped_truth():
    """independent() of the damped scene, once for its five tests: at every FINEST step, each
    run's rows picked from its times (solve_ivp's steps do not depend on t_eval)."""
    t = FINEST * np.arange(round(deck("exact")["analysis"]["duration"] / FINEST) + 1)
    x, att, omega = independent(t, dampers=DAMPERS)

    def at(times: np.ndarray):
        rows = np.rint(times / FINEST).astype(int)
        assert np.allclose(t[rows], times, rtol=0.0, atol=1e-12)
        return x[rows], att[rows], omega[rows]

    return at


@pytest.mark.parametrize("integrator", ["adaptive", *FIXED_STEP])
def test_dampers_turn_with_the_body_in_space(tmp_path, integrator, damped_truth):
    data = deck("exact")
    data["dampers"] = [{"point": list(p), "direction": list(d), "c": c} for p, d, c in DAMPERS]
    sc = scene(data, tmp_path)
    if integrator == "adaptive":
        res = run(sc, **ADAPTIVE)
        x, att, omega = damped_truth(res.time)
        assert rel(res.d[:, :3], x) < 1e-6 and rel(res.d[:, 3:], att.as_rotvec()) < 1e-6
        assert rel(res.v[:, 3:], omega) < 1e-6
        assert res.energy_balance < 1e-7
        return
    errs = []
    dts = (2e-3, 1e-3, 5e-4)
    for dt in dts:
        res = run(sc, integrator=integrator, dt=dt)
        _, att, _ = damped_truth(res.time)
        errs.append(rel(res.d[:, 3:], att.as_rotvec()))
    order = math.log(errs[0] / errs[-1]) / math.log(dts[0] / dts[-1])
    assert order == pytest.approx(2.0, abs=0.25), errs
    assert res.energy_balance < 1e-3
