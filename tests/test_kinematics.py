"""Exact planar kinematics (analysis.kinematics = "exact") against an independent integration of
the exact equations of a square body on linear springs, written here from forces and moments
(not from the rows b_e(q) the kernels use); and small against exact on small motions."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from conftest import linear_set
from rbhyst.model.deck import parse_deck
from rbhyst.model.settings import settings_from_deck
from rbhyst.model.system import assemble
from rbhyst.solve.plan import simulate

K, MASS, C = 2.0e4, 500.0, 0.5  # N/m each spring, kg, half side (m)
J = MASS * (2 * C) ** 2 / 6.0  # a uniform square about G
#: the springs: point from G, line of action (angle); at the corners, so that each point also
#: lies along its line (d . r != 0) and the rows turn with the body
SPRINGS = (((C, C), 0.0), ((-C, -C), 0.0), ((C, -C), 90.0), ((-C, C), 90.0), ((C, 0.0), 45.0))
PULSE = {"type": "half-sine", "units": "N m", "duration": 0.25}
MOMENT, FORCE = 4.0e3, 1.5e3  # N m, N: peaks of the half-sine pulses
FIXED_STEP = ("chang", "central-difference", "newmark", "kr-alpha")


def deck(kinematics: str, moment: float, force: float = 0.0, duration: float = 1.5, dt: float = 1e-3) -> dict:
    out = {
        "body": {"vertices": [[-C, -C], [C, -C], [C, C], [-C, C]], "mass": MASS},
        "hysteresis": {"lin": linear_set(K)},
        "elements": [{"point": list(x), "angle_deg": a, "hysteresis": "lin"} for x, a in SPRINGS],
        "excitation": {"force": {"m3": dict(PULSE, amplitude=moment)}},
        "analysis": {"dt": dt, "duration": duration, "kinematics": kinematics},
        "output": {"points": [{"name": "corner", "point": [C, C]}]},
    }
    if force:
        out["excitation"]["force"]["p1"] = {"type": "half-sine", "units": "N", "duration": 0.25, "amplitude": force}
    return out


def scene(data, tmp_path):
    """(System, Settings) of a deck given as a dict."""
    d = parse_deck(data)
    return assemble(d, tmp_path), dataclasses.replace(settings_from_deck(d), estimate=False)


def run(scene_, **overrides):
    system, settings = scene_
    return simulate(system, dataclasses.replace(settings, **overrides))


ADAPTIVE = {"integrator": "adaptive", "rtol": 1e-11}


def exact_rhs(t, y, moment: float, force: float, at=(0.0, 0.0), dampers=()) -> list:
    """d/dt (x1, x2, theta, v1, v2, omega) of the exact planar equations: each spring along its
    fixed direction d pulls at its body point, now at x_G + R(theta) r, with the force
    -k (d . u_P) d, whose moment about G is (R r) x F; p1 acts at the body point ``at``."""
    def pulse(amp):
        return amp * math.sin(math.pi * t / 0.25) if t < 0.25 else 0.0

    x1, x2, th, v1, v2, w = y
    c, s = math.cos(th), math.sin(th)
    f1 = pulse(force)
    f2 = 0.0
    # the moment of p1 at the turned point, and the pulse moment
    m = pulse(moment) - (s * at[0] + c * at[1]) * f1
    for (r1, r2), a in SPRINGS:
        d1, d2 = math.cos(math.radians(a)), math.sin(math.radians(a))
        p1, p2 = c * r1 - s * r2, s * r1 + c * r2  # R r
        u = d1 * (x1 + p1 - r1) + d2 * (x2 + p2 - r2)
        fx, fy = -K * u * d1, -K * u * d2
        f1 += fx
        f2 += fy
        m += p1 * fy - p2 * fx
    for (r1, r2), a, c_d in dampers:  # a damper along its fixed line, on its turned point's velocity
        d1, d2 = math.cos(math.radians(a)), math.sin(math.radians(a))
        p1, p2 = c * r1 - s * r2, s * r1 + c * r2
        rate = d1 * (v1 - w * p2) + d2 * (v2 + w * p1)
        fx, fy = -c_d * rate * d1, -c_d * rate * d2
        f1 += fx
        f2 += fy
        m += p1 * fy - p2 * fx
    return [v1, v2, w, f1 / MASS, f2 / MASS, m / J]


def independent(moment: float, force: float, t_out: np.ndarray, at=(0.0, 0.0), dampers=()) -> np.ndarray:
    """(len(t_out), 6) the exact planar equations (exact_rhs) integrated by scipy's DOP853 at rtol 1e-12."""
    sol = solve_ivp(exact_rhs, (0.0, t_out[-1]), np.zeros(6), method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=t_out, max_step=0.01, args=(moment, force, at, dampers))
    assert sol.success
    return sol.y.T


@pytest.fixture(scope="module")
def large(tmp_path_factory):
    """A moment pulse that turns the body by about 0.3 rad."""
    return scene(deck("exact", moment=MOMENT, force=FORCE), tmp_path_factory.mktemp("k"))


def test_the_scene_rotates_beyond_the_small_angles(large):
    res = run(large, **ADAPTIVE)
    assert 0.25 < np.max(np.abs(res.d[:, 2])) < 0.5


def test_exact_kinematics_agree_with_an_independent_integration(large):
    res = run(large, **ADAPTIVE)
    ref = independent(MOMENT, FORCE, res.time)
    for i in range(3):
        err = np.max(np.abs(res.d[:, i] - ref[:, i])) / np.max(np.abs(ref[:, i]))
        assert err < 1e-6, (i, err)
    # velocities as well; and the point's motion follows R(theta) exactly
    for i in range(3):
        err = np.max(np.abs(res.v[:, i] - ref[:, 3 + i])) / np.max(np.abs(ref[:, 3 + i]))
        assert err < 1e-6, (i, err)
    th = ref[:, 2]
    corner = np.column_stack([ref[:, 0] + C * np.cos(th) - C * np.sin(th) - C,
                              ref[:, 1] + C * np.sin(th) + C * np.cos(th) - C])
    got = np.column_stack([res.column("corner_u1_m"), res.column("corner_u2_m")])
    assert np.max(np.abs(got - corner)) < 1e-6 * np.max(np.abs(corner))


@pytest.mark.parametrize("integrator", FIXED_STEP)
def test_every_fixed_step_method_converges_to_the_exact_solution_at_its_order(large, integrator):
    errs = []
    dts = (2e-3, 1e-3, 5e-4)
    for dt in dts:
        res = run(large, integrator=integrator, dt=dt)
        ref = independent(MOMENT, FORCE, res.time)
        errs.append(np.max(np.abs(res.d[:, 2] - ref[:, 2])) / np.max(np.abs(ref[:, 2])))
    assert errs[-1] < 2e-3
    order = math.log(errs[0] / errs[-1]) / math.log(dts[0] / dts[-1])
    assert order == pytest.approx(2.0, abs=0.25), errs
    # the energy balance closes to the method's accuracy with the rows turning
    assert res.energy_balance < 1e-3


def test_total_accelerations_of_a_point_carry_the_centripetal_term(large):
    res = run(large, **ADAPTIVE)
    th, w, al = res.d[:, 2], res.v[:, 2], res.column("alphat3_rad_s2")
    r1, r2 = C * np.cos(th) - C * np.sin(th), C * np.sin(th) + C * np.cos(th)
    want1 = res.column("at1_m_s2") - al * r2 - w * w * r1
    want2 = res.column("at2_m_s2") + al * r1 - w * w * r2
    assert np.max(np.abs(res.column("corner_at1_m_s2") - want1)) < 1e-9 * np.max(np.abs(want1))
    assert np.max(np.abs(res.column("corner_at2_m_s2") - want2)) < 1e-9 * np.max(np.abs(want2))
    # the moment resultant is the springs' exact moment about G at each row
    ref = independent(MOMENT, FORCE, res.time)
    assert np.max(np.abs(res.d[:, 2] - ref[:, 2])) < 1e-6


def test_small_and_exact_agree_to_second_order_in_the_rotation(tmp_path):
    """Halving the motion quarters the difference of the two models (m, the rotation at the
    body's half side)."""
    diffs = []
    for amp in (24.0, 12.0):
        runs = {kin: run(scene(deck(kin, moment=amp, force=amp / 1.6), tmp_path), **ADAPTIVE)
                for kin in ("small", "exact")}
        theta = np.max(np.abs(runs["exact"].d[:, 2]))
        scale = np.array([1.0, 1.0, C])
        diffs.append((theta, np.max(np.abs((runs["small"].d - runs["exact"].d) * scale))))
    (t1, d1), (t2, d2) = diffs
    assert t1 == pytest.approx(2 * t2, rel=1e-3)
    assert d1 < 10 * C * t1 * t1  # (a phase the two models drift apart by over the run)
    assert d1 / d2 == pytest.approx(4.0, rel=0.05)


def test_small_kinematics_keep_the_seed_rows(tmp_path):
    small, _ = scene(deck("small", moment=1.0), tmp_path)
    exact, _ = scene(deck("exact", moment=1.0), tmp_path)
    assert small.kinematics == "small" and small.axial is None and small.rotation_index == -1
    assert exact.rotation_index == 2
    np.testing.assert_array_equal(small.bvec, exact.bvec)
    np.testing.assert_allclose(exact.axial, [C, -C, -C, C, C / math.sqrt(2)], atol=1e-15)


def test_a_small_rotation_run_reports_the_error_its_kinematics_carry(tmp_path):
    """The large scene run with the seed's kinematics: summary's ``kinematics`` holds the
    difference from the exact run, per column, and a warning names it in numbers."""
    from rbhyst.results.analysis import analyse

    system, settings = scene(deck("small", moment=MOMENT, force=FORCE), tmp_path)
    res = analyse(system, dataclasses.replace(settings, integrator="chang", dt=5e-4), keep=True)
    kin = res.kinematics
    assert kin["model"] == "small" and kin["max_rotation_rad"] > 0.25
    # against an exact run of its own: the same numbers
    exact_sys, _ = scene(deck("exact", moment=MOMENT, force=FORCE), tmp_path)
    exact = simulate(exact_sys, dataclasses.replace(settings, integrator="chang", dt=5e-4))
    want = np.max(np.abs(res.column("theta3_rad") - exact.column("theta3_rad"))) / np.max(np.abs(exact.column("theta3_rad")))
    assert kin["difference"]["theta3"] == pytest.approx(want, rel=1e-6)
    assert kin["worst"]["difference"] > 0.05
    said = [w for w in res.warnings if "small rotations" in w]
    assert len(said) == 1 and 'analysis.kinematics = "exact"' in said[0] and kin["worst"]["column"] in said[0]
    assert "kinematics" in res.summary()


def test_a_barely_turning_run_pays_nothing_and_says_why(tmp_path):
    from rbhyst.results.analysis import analyse

    system, settings = scene(deck("small", moment=2.0), tmp_path)
    res = analyse(system, settings, keep=True)
    kin = res.kinematics
    assert kin["difference"] is None and kin["neglected"]["share"] < 1e-3
    assert kin["max_rotation_rad"] < 1e-3 and "not computed" in kin["method"]
    assert not [w for w in res.warnings if "rotation" in w]


@pytest.mark.parametrize("integrator", ("adaptive",) + FIXED_STEP)
def test_a_force_away_from_g_turns_its_arm_with_the_body(tmp_path, integrator):
    """p1 at a top corner: its moment about G is (R r) x p at every instant (the load's two
    extra columns), against the independent integration; the fixed-step methods to their
    order's accuracy at 0.25 ms."""
    data = deck("exact", moment=MOMENT, force=FORCE)
    data["excitation"]["force"]["point"] = [C, C]
    sc = scene(data, tmp_path)
    assert sc[0].excitation.follow and sc[0].excitation.width == 5
    res = run(sc, **(ADAPTIVE if integrator == "adaptive" else {"integrator": integrator, "dt": 2.5e-4}))
    ref = independent(MOMENT, FORCE, res.time, at=(C, C))
    err = np.max(np.abs(res.d[:, 2] - ref[:, 2])) / np.max(np.abs(ref[:, 2]))
    assert err < (1e-6 if integrator == "adaptive" else 2e-3), err
    assert np.max(np.abs(ref[:, 2])) > 0.2
    # the total accelerations are the equation of motion's with the turned arm
    if integrator == "adaptive":
        want = np.array([exact_rhs(t, y, MOMENT, FORCE, (C, C))[5] for t, y in zip(res.time, ref)])
        assert np.max(np.abs(res.column("alphat3_rad_s2") - want)) < 1e-5 * np.max(np.abs(want))
    assert res.energy_balance < 1e-3


def test_the_neglected_terms_flag_a_scene_before_the_rotation_does(tmp_path):
    """Mounts level with G under a lateral force: the shear forces' moment arm turns with the
    body (f c sin theta), a large share of the small rocking moment; the indicator sees it, the
    exact twin runs and measures what the seed's rows miss, above theta / 2."""
    from rbhyst.results.analysis import analyse

    data = deck("small", moment=0.0, force=2.0e3)
    data["excitation"]["force"].pop("m3")
    res = analyse(*scene(data, tmp_path), keep=True)
    kin = res.kinematics
    assert kin["difference"] is not None
    assert kin["worst"]["difference"] > 3 * kin["max_rotation_rad"] / 2  # (6.3 times here)
    assert kin["neglected"]["share"] > 0.1 * res.settings.warn_error


def test_the_modes_at_rest_feel_the_weight_with_exact_kinematics(tmp_path):
    """A square on four vertical springs at its base corners and two horizontal ones at G's
    level, under gravity: with exact rows, the rocking stiffness at rest is k_v sum x^2 less the
    weight's W h (P-Delta, h = the half side from the springs up to G), which the seed's rows lack."""
    from rbhyst.solve.modes import tangent_at_rest

    kv, kh = 2.0e5, 1.0e5
    data = {
        "body": {"vertices": [[-C, -C], [C, -C], [C, C], [-C, C]], "mass": MASS, "gravity": [0.0, -9.81]},
        "hysteresis": {"v": linear_set(kv), "h": linear_set(kh)},
        "elements": [{"point": [C, -C], "angle_deg": 90.0, "hysteresis": "v"},
                     {"point": [-C, -C], "angle_deg": 90.0, "hysteresis": "v"},
                     {"point": [C, 0.0], "angle_deg": 0.0, "hysteresis": "h"},
                     {"point": [-C, 0.0], "angle_deg": 0.0, "hysteresis": "h"}],
        "analysis": {"dt": 1e-3, "duration": 0.1},
    }
    weight = MASS * 9.81
    for kin, want in (("small", 2 * kv * C * C), ("exact", 2 * kv * C * C - weight * C)):
        data["analysis"]["kinematics"] = kin
        system, _ = scene(data, tmp_path)
        k = tangent_at_rest(system)
        assert k[2, 2] == pytest.approx(want, rel=1e-9), kin


#: two dampers at corners, off their lines (their rows turn): point, angle, c (N s/m)
DAMPERS = (((C, -C), 0.0, 900.0), ((-C, C), 60.0, 1500.0))


@pytest.mark.parametrize("integrator", ["adaptive", *FIXED_STEP])
def test_dampers_turn_with_the_body_under_exact_kinematics(tmp_path, integrator):
    """Viscous dampers along lines fixed in the ground, at points that turn: the adaptive solution
    agrees with the independent integration to 1e-6, every fixed-step method converges at order 2
    with its energy balance (the viscous work included) closed."""
    data = deck("exact", moment=MOMENT, force=FORCE, duration=1.2)
    data["dampers"] = [{"point": list(x), "angle_deg": a, "c": c} for x, a, c in DAMPERS]
    sc = scene(data, tmp_path)
    if integrator == "adaptive":
        res = run(sc, **ADAPTIVE)
        ref = independent(MOMENT, FORCE, res.time, dampers=DAMPERS)
        assert 0.15 < np.max(np.abs(res.d[:, 2]))  # well beyond the small angles, damped
        for i in range(3):
            assert np.max(np.abs(res.d[:, i] - ref[:, i])) < 1e-6 * np.max(np.abs(ref[:, i])), i
        assert res.energy_balance < 1e-7
        # the dampers' columns: each one's rate along its line at its turned point
        th, w = ref[:, 2], ref[:, 5]
        (r1, r2), a, _ = DAMPERS[0]
        rate = ref[:, 3] - w * (np.sin(th) * r1 + np.cos(th) * r2)
        assert np.max(np.abs(res.column("d1_v_m_s") - rate)) < 1e-6 * np.max(np.abs(rate))
        return
    errs = []
    dts = (2e-3, 1e-3, 5e-4)
    for dt in dts:
        res = run(sc, integrator=integrator, dt=dt)
        ref = independent(MOMENT, FORCE, res.time, dampers=DAMPERS)
        errs.append(np.max(np.abs(res.d[:, 2] - ref[:, 2])) / np.max(np.abs(ref[:, 2])))
    order = math.log(errs[0] / errs[-1]) / math.log(dts[0] / dts[-1])
    assert order == pytest.approx(2.0, abs=0.25), errs
    assert res.energy_balance < 1e-3


@pytest.mark.parametrize("integrator", FIXED_STEP)
def test_every_method_keeps_its_order_with_viscous_dampers(tmp_path, integrator):
    """With the seed's small rotations and two dampers: order 2 against the adaptive solution at
    rtol 1e-12 (KR-alpha's velocity update once carried C and made a damped run first order)."""
    data = deck("small", moment=MOMENT, force=FORCE, duration=1.2)
    data["dampers"] = [{"point": list(x), "angle_deg": a, "c": c} for x, a, c in DAMPERS]
    sc = scene(data, tmp_path)
    errs = []
    dts = (2e-3, 1e-3, 5e-4)
    for dt in dts:
        res = run(sc, integrator=integrator, dt=dt)
        ref = run(sc, integrator="adaptive", rtol=1e-12, dt=dt)
        errs.append(np.max(np.abs(res.d[:, 2] - ref.d[:, 2])) / np.max(np.abs(ref.d[:, 2])))
    order = math.log(errs[0] / errs[-1]) / math.log(dts[0] / dts[-1])
    assert order == pytest.approx(2.0, abs=0.2), errs


def test_the_resultant_s_neglected_forces_are_the_elements_summed(tmp_path, monkeypatch):
    """The small rotations' check of the forces' resultant (model_residual) sums the elements'
    neglected forces per row without an array of them: against each element's neglected
    deformation b3 (sin theta - theta) + c (cos theta - 1) times its reversal stiffness along
    its direction, summed over the elements here, at every compared row (the series summed
    smallest first where numpy's sin(theta) - theta would lose the digits)."""
    from rbhyst.model.system import axial_offset
    from rbhyst.results.analysis import analyse
    from rbhyst.solve import kinematic
    from rbhyst.solve.history import estimate_columns

    data = deck("small", moment=0.0, force=2.0e3)
    data["excitation"]["force"].pop("m3")
    seen = []
    real = kinematic.resultant_share
    monkeypatch.setattr(kinematic, "resultant_share", lambda dr, *a: seen.append(np.array(dr)) or real(dr, *a))
    res = analyse(*scene(data, tmp_path), keep=True)
    assert len(seen) == 1
    system = res.system
    columns = [k for k, _, _ in estimate_columns(res.layout)]
    start = float(system.static.q[2]) if system.static is not None else 0.0
    theta = start + res.compared[:, 1 + columns.index(system.coordinates[2].key("d"))]
    assert 1e-3 < np.max(np.abs(theta)) < 0.25
    want = np.zeros(2)
    elements = [el for el in system.elements for _ in range(el.count)]
    k_rev = system.expand(system.k_reversal[None, :])[0]
    for th in theta:
        s = sum(reversed([(-1) ** k * th ** (2 * k + 1) / math.factorial(2 * k + 1) for k in range(1, 8)]))
        m = sum(reversed([(-1) ** k * th ** (2 * k) / math.factorial(2 * k) for k in range(1, 8)]))
        force = np.zeros(2)
        for el, k in zip(elements, k_rev):
            a = math.radians(el.angle_deg)
            b3 = el.x[0] * math.sin(a) - el.x[1] * math.cos(a)  # (its row b_e's rotation term)
            du = b3 * s + axial_offset(el.x[0], el.x[1], a) * m
            force += du * k * np.array([math.cos(a), math.sin(a)])
        want = np.maximum(want, np.abs(force))
    assert np.allclose(seen[0], want, rtol=1e-12, atol=1e-12 * np.max(want)), (seen[0], want)
    assert np.max(want) > 0
