"""Coupled shear of [[isolators]] (``coupling = "mss"``, rbhyst.model.mss): a multiple shear spring
reproduces its set along a shear line, bears the same force in every direction of its plane, and a
symmetric body on such isolators answers a turned motion as the motion along x1; with independent
shear springs ("none") it does not."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import TABLE3_SHEAR, invoke, write_deck

from rbhyst.model.hysteresis import parameter_set
from rbhyst.model.mss import spring_cosines, spring_set
from rbhyst.model.vrm import loop

#: a wire rope isolator's shear set without exponential term (kb 2e4 N/m, f0 800 N, alpha 200 /m)
SOFT = parameter_set({"kb": 2.0e4, "f0": 800.0, "alpha": 200.0}, {"kb": 2.0e4, "f0": 800.0, "alpha": 200.0})


def _table3() -> np.ndarray:
    return parameter_set(*(TABLE3_SHEAR[k] for k in ("loading", "unloading")))


def _cycle(a: float) -> np.ndarray:
    return a * np.concatenate([np.linspace(0, 1, 800), np.linspace(1, -1, 1600)[1:], np.linspace(-1, 1, 1600)[1:]])


def _mss_along(q: np.ndarray, n: int, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The resultant (along shear lines 1 and 2) of n springs of set q under the shear motion
    (u1, u2), each driven by its projection: written here from the definition."""
    c, s = spring_cosines(n)
    f1 = np.zeros_like(u1)
    f2 = np.zeros_like(u1)
    for ci, si in zip(c, s):
        f = loop(q, ci * u1 + si * u2)[0]
        f1 += ci * f
        f2 += si * f
    return f1, f2


@pytest.mark.parametrize("line", [0, 1])
@pytest.mark.parametrize("amplitude", [0.003, 0.01, 0.03])
def test_uniaxial_cycle_reproduces_the_set(line, amplitude):
    """Along either shear line the MSS's loop is the set's within 7 % of its peak force for
    amplitudes up to its reference (8 springs, seed Table 3 shear set)."""
    p = _table3()
    q = spring_set(p, 8, 0.03)
    u = _cycle(amplitude)
    f = loop(p, u)[0]
    zero = np.zeros_like(u)
    f1, _ = _mss_along(q, 8, u, zero) if line == 0 else _mss_along(q, 8, zero, u)[::-1]
    assert np.max(np.abs(f1 - f)) <= 0.07 * np.max(np.abs(f))
    # nothing across the line it moves along where the set's branches mirror each other
    g1, g2 = _mss_along(spring_set(SOFT, 8, None), 8, *((u, zero) if line == 0 else (zero, u)))
    assert np.max(np.abs(g2 if line == 0 else g1)) <= 1e-9 * np.max(np.abs(g1 if line == 0 else g2))


def test_scaling_is_exact_at_both_ends():
    """The springs' stiffness along a shear line at a reversal is the set's, and the saturated
    force of a set without exponential term is its kb u + f0."""
    q = spring_set(SOFT, 8, None)
    c, _ = spring_cosines(8)
    k_spring = q[0, 0] + q[0, 2] * (q[0, 1] + q[1, 1])
    assert np.sum(k_spring * c**2) == pytest.approx(SOFT[0, 0] + SOFT[0, 2] * 1600.0, rel=1e-12)
    u = np.linspace(0.0, 0.2, 2001)  # alpha u = 40: every spring but the one across is saturated
    f1, _ = _mss_along(q, 8, u, 0 * u)
    assert f1[-1] == pytest.approx(loop(SOFT, u)[0][-1], rel=1e-6)


def test_circular_orbit_bears_one_force_in_every_direction():
    """A circular orbit well beyond yield: the MSS's resultant varies by no more than 3 % around
    it; two independent springs along the shear lines carry up to sqrt(2) more on a diagonal."""
    r = 0.05  # alpha r = 10
    t = np.linspace(0.0, 3.0, 6001)  # three turns, from the centre out along x1 first
    ramp = np.minimum(t / 0.25, 1.0)
    u1 = r * ramp * np.cos(2 * math.pi * t)
    u2 = r * ramp * np.sin(2 * math.pi * t)
    last = t >= 2.0
    f1, f2 = _mss_along(spring_set(SOFT, 8, None), 8, u1, u2)
    mag = np.hypot(f1, f2)[last]
    assert mag.max() / mag.min() - 1.0 <= 0.03
    g = np.hypot(loop(SOFT, u1)[0], loop(SOFT, u2)[0])[last]
    assert g.max() / g.min() > 1.3


def _box(coupling: str, turn_deg: float) -> dict:
    """A square box 0.6 x 0.6 x 1 m on four isolators at its bottom corners under a sine along
    x1, or the same sine turned by turn_deg about x3."""
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    sine = {"type": "sine", "frequency_hz": 2.0, "units": "m/s2", "cycles": 3, "ramp_cycles": 1}
    support = {"x1": {**sine, "amplitude": 6.0 * c}}
    if turn_deg:
        support["x2"] = {**sine, "amplitude": 6.0 * s}
    iso = {"axial": [0.0, 0.0, -1.0], "hysteresis": {"axial": "axial", "shear": "shear"}}
    if coupling == "mss":
        iso["coupling"] = "mss"
    branch = {"kb": 2.0e4, "f0": 800.0, "alpha": 200.0}
    return {
        "body": {"box": {"size": [0.6, 0.6, 1.0], "centre": [0.3, 0.3, 0.5]}, "mass": 400.0},
        "hysteresis": {"shear": {"loading": branch, "unloading": branch},
                       "axial": {"loading": {"kb": 2e6, "f0": 100.0, "alpha": 10.0},
                                 "unloading": {"kb": 2e6, "f0": 100.0, "alpha": 10.0}}},
        "isolators": [{"vertex": v, **iso} for v in (1, 2, 3, 4)],
        "excitation": {"support": support},
        "analysis": {"dt": 0.001, "duration": 2.0, "integrator": "newmark"},
    }


def _peaks(tmp_path, data, name):
    from rbhyst.api import run

    res = run(write_deck(tmp_path, data, name), estimate=False)
    u = np.hypot(res.column("u1_m"), res.column("u2_m"))
    a = np.hypot(res.column("at1_m_s2"), res.column("at2_m_s2"))
    return u.max(), a.max(), np.max(np.abs(res.column("u2_m"))), res


@pytest.mark.parametrize("coupling", ["mss", "none"])
def test_turned_motion_gives_the_same_answer(tmp_path, coupling):
    """MSS: the motion turned by 30 deg about x3 gives G the same peak horizontal displacement
    and total acceleration within 1 %, and the motion along x1 no cross motion; independent
    shear springs turn out otherwise (the test that fails with them)."""
    u0, a0, cross, res = _peaks(tmp_path, _box(coupling, 0.0), "along")
    u30, a30, _, _ = _peaks(tmp_path, _box(coupling, 30.0), "turned")
    assert u0 > 5 * 800.0 / 4 / 2.0e4 / 10  # well beyond yield: the test is about the plastic range
    differ = max(abs(u30 / u0 - 1.0), abs(a30 / a0 - 1.0))
    if coupling == "mss":
        assert differ <= 0.01
        assert cross <= 1e-9 * u0
        assert abs(res.column("E_error_J")).max() <= 1e-3 * np.abs(res.column("E_input_J")).max()
    else:
        assert differ > 0.01


def test_mss_columns_are_the_shear_lines(tmp_path):
    """iso<k>_shear<j> columns: the springs' deformation projected back and their resultant."""
    from rbhyst.api import run

    res = run(write_deck(tmp_path, _box("mss", 30.0), "cols"), estimate=False)
    # the bottom corner's shear displacement along x1 is G's plus the rotation's share; at
    # vertex 1 under the default shear lines (x1, x2) the columns are the springs' projections
    c, s = spring_cosines(8)
    us = np.column_stack([res.column(f"e{k}_u_m") for k in range(2, 10)])
    fs = np.column_stack([res.column(f"e{k}_f_N") for k in range(2, 10)])
    assert np.allclose(res.column("iso1_shear1_u_m"), us @ c / 4.0, rtol=0, atol=1e-15)
    assert np.allclose(res.column("iso1_shear2_f_N"), fs @ s, rtol=0, atol=1e-9)


@pytest.mark.parametrize("change, line", [
    ({"coupling": "mss", "springs": 7}, "isolators[1].springs: 7: an even number"),
    ({"springs": 8}, "isolators[1].springs: goes with coupling = \"mss\""),
    ({"coupling": "mss", "stroke": {"shear": 0.05}}, "isolators[1].stroke.shear: not with coupling"),
])
def test_mss_mistakes_are_one_line(tmp_path, change, line):
    data = _box("none", 0.0)
    data["isolators"][0].update(change)
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots", "--out", tmp_path / "o")
    assert code == 2 and line in err and "Traceback" not in err


def test_plane_refuses_mss(tmp_path):
    from conftest import seed_deck

    data = seed_deck()
    data.pop("elements", None)
    data["isolators"] = [{"vertex": 1, "axial_deg": 270.0, "coupling": "mss",
                          "hysteresis": {"axial": next(iter(data["hysteresis"])), "shear": next(iter(data["hysteresis"]))}}]
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots", "--out", tmp_path / "o")
    assert code == 2 and "isolators[1].coupling: \"mss\" couples two shear lines" in err


def test_exponential_set_needs_a_reference(tmp_path):
    data = _box("mss", 0.0)
    data["hysteresis"]["shear"] = {k: dict(v) for k, v in TABLE3_SHEAR.items()}
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots", "--out", tmp_path / "o")
    assert code == 2 and "isolators[1].reference: required with coupling = \"mss\"" in err
