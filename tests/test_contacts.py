"""[[contacts]]: points resting on the ground, compression only (a zero-VRM element with a one-sided
stop, rbhyst.model.stop). A body rests on them with its weight, a dropped block bounces as the
restitution says in closed form, a rigid block starts to rock at g b / h, and no contact pulls."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import invoke, linear_set, write_deck

from rbhyst import api
from rbhyst.model.deck import parse_deck

B, H, M, G = 0.2, 0.5, 100.0, 9.80665  # half width, height of G above the base, mass, gravity
K_CONTACT, E = 1e8, 0.5


def block(dt: float = 2e-4, duration: float = 1.0, integrator: str = "newmark", gap: float = 0.0,
          gravity: bool = True) -> dict:
    """A 2B x 2H block on contacts at its two bottom corners (normal x2), held along x1 at the middle
    of its base by a stiff linear spring (contacts are frictionless): the spring acts at the base,
    so a ground acceleration a along x1 overturns it by M a H about the base, as on friction."""
    d = {"body": {"vertices": [[-B, 0.0], [B, 0.0], [B, 2 * H], [-B, 2 * H]], "mass": M},
         "hysteresis": {"lin": linear_set(2e6)},
         "elements": [{"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "lin"}],
         "contacts": [{"vertex": v, "normal": [0.0, 1.0], "stiffness": K_CONTACT, "restitution": E, "gap": gap}
                      for v in (1, 2)],
         "analysis": {"dt": dt, "duration": duration, "integrator": integrator}}
    if gravity:
        d["body"]["gravity"] = [0.0, -G]
    return d


def weight_from_rest(folder) -> dict:
    """The weight as a force along x2 from t = 0 (a record of two samples, constant between them):
    the block is released from rest where it is, GAP above its contacts (body.gravity would put it
    at rest on them)."""
    path = folder / "weight.csv"
    path.write_text(f"0.0,{-M * G!r}\n100.0,{-M * G!r}\n")
    return {"force": {"p2": {"type": "record", "file": str(path), "units": "N"}}}


def speed_ratio(apex: float, gap: float) -> float:
    """Rebound over approach speed at the gap of a block that fell ``gap`` from rest and climbs back
    to ``apex`` (u2 of G, from rest): v^2 = 2 g (height)."""
    return float(np.sqrt((apex + gap) / gap))


def run(data: dict):
    return api.run(parse_deck(data), estimate=False)


def test_a_body_rests_on_its_contacts_with_its_weight_and_stays_at_rest():
    r = run(block())
    static = r.summary()["static"]["elements"]
    assert [e["f_N"] for e in static[1:]] == pytest.approx([-M * G / 2] * 2, rel=1e-9)
    assert static[1]["u_m"] == pytest.approx(-M * G / 2 / K_CONTACT, rel=1e-9)
    f = r.column("e2_f_N")
    assert np.all(f == f[0]) and f[0] == pytest.approx(-M * G / 2, rel=1e-9)
    assert all(e["stop"]["impacts"] == 0 for e in r.summary()["elements"][1:])


def test_a_box_in_space_rests_on_four_contacts():
    d = {"body": {"box": {"size": [0.4, 0.6, 1.0], "centre": [0.0, 0.0, 0.5]}, "mass": M, "gravity": [0.0, 0.0, -G]},
         "hysteresis": {"lin": linear_set(2e6)},
         "elements": [{"point": [0.0, 0.0, 0.0], "direction": v, "hysteresis": "lin"}
                      for v in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])]
         + [{"point": [0.2, 0.0, 0.0], "direction": [0.0, 1.0, 0.0], "hysteresis": "lin"}],
         "contacts": [{"point": [x, y, 0.0], "normal": [0.0, 0.0, 1.0], "stiffness": K_CONTACT, "restitution": E}
                      for x in (-0.2, 0.2) for y in (-0.3, 0.3)],
         "analysis": {"dt": 2e-4, "duration": 0.2, "integrator": "newmark"}}
    static = run(d).summary()["static"]["elements"]
    assert [e["f_N"] for e in static[3:]] == pytest.approx([-M * G / 4] * 4, rel=1e-9)


@pytest.mark.parametrize("integrator, dt, tol", [("newmark", 2.5e-5, 2e-3), ("reference", 1e-4, 1e-5)])
def test_a_dropped_block_bounces_with_the_restitution(tmp_path, integrator, dt, tol):
    """Released from rest GAP above its contacts (weight_from_rest): it lands at
    v = sqrt(2 g GAP), loads the contacts to d_max where 0.5 M v^2 + M g d = K_CONTACT d^2 (two of
    them) and leaves at the gap with the kinetic energy less 2 x 0.5 K d^2 (1 - E^2)."""
    gap = 0.01
    d = block(dt=dt, duration=0.12, integrator=integrator, gap=gap, gravity=False)
    d["excitation"] = weight_from_rest(tmp_path)
    r = run(d)
    u = r.column("u2_m")
    v_in = np.sqrt(2.0 * G * gap)
    dm = (M * G + np.sqrt((M * G) ** 2 + 4.0 * K_CONTACT * 0.5 * M * v_in**2)) / (2.0 * K_CONTACT)
    ratio = np.sqrt(1.0 - K_CONTACT * dm**2 * (1.0 - E * E) / (0.5 * M * v_in**2))
    # the rebound's speed at the gap from the height it climbs to (free flight both ways: the rows'
    # velocities straddle the contact's start within a step)
    landed = int(np.argmax(u < -gap))
    apex = float(np.max(u[landed:]))
    assert speed_ratio(apex, gap) == pytest.approx(ratio, rel=tol)
    assert float(np.min(u)) == pytest.approx(-gap - dm, rel=tol)
    assert ratio == pytest.approx(E, rel=0.05)  # the restitution, less what gravity adds to the impact
    assert np.all(r.column("e2_f_N") <= 0.0) and np.all(r.column("e3_f_N") <= 0.0)
    assert r.energy_balance < 1e-3


def test_a_dropped_block_comes_to_rest_on_its_contacts_with_its_weight(tmp_path):
    d = block(dt=1e-4, duration=1.5, gap=0.005, gravity=False)
    d["excitation"] = weight_from_rest(tmp_path)
    d["dampers"] = [{"point": [0.0, 0.0], "angle_deg": 90.0, "c": 2000.0}]
    r = run(d)
    carried = r.column("e2_f_N")[-1] + r.column("e3_f_N")[-1]
    assert carried == pytest.approx(-M * G, rel=1e-3)
    assert abs(r.column("v2_m_s")[-1]) < 1e-4
    assert r.summary()["elements"][1]["stop"]["impacts"] >= 2


@pytest.mark.parametrize("integrator", ["newmark", "reference"])
def test_a_rigid_block_starts_to_rock_at_g_b_over_h_and_lands_again(integrator):
    """A slow ramp of ground acceleration along x1 (0 to 0.44 g over 2.2 s, then none): the
    contact on the far side lets go where a = g B / H (quasi-static: M a H = M g B about the
    near corner), within 1 %; the block rocks and lands on it again; no contact ever pulls."""
    d = block(duration=3.0, integrator=integrator)
    top, rise = 0.44, 2.2
    d["excitation"] = {"support": {"x1": {"type": "terminal-peak-sawtooth", "amplitude": top, "duration": rise,
                                          "units": "g"}}}
    r = run(d)
    t, near, far = r.column("time_s"), r.column("e2_f_N"), r.column("e3_f_N")
    lifts = int(np.argmax(far == 0.0))
    assert lifts > 0
    onset = top * t[lifts] / rise
    assert onset == pytest.approx(B / H, rel=0.01)
    assert np.all(near <= 0.0) and np.all(far <= 0.0)
    assert np.any(far[lifts:] < 0.0)  # it landed
    assert r.summary()["elements"][2]["stop"]["impacts"] >= 1


def test_friction_is_refused_in_one_line(tmp_path):
    d = block()
    d["contacts"][0]["friction"] = 0.3
    code, err = invoke("run", write_deck(tmp_path, d), "--out", tmp_path / "out")
    assert code == 2
    lines = [ln for ln in err.splitlines() if "contacts[1].friction" in ln]
    assert len(lines) == 1 and "frictionless" in lines[0], err


def test_a_contact_normal_of_the_wrong_dimension_is_named(tmp_path):
    d = block()
    d["contacts"][1]["normal"] = [0.0, 0.0, 1.0]
    code, err = invoke("run", write_deck(tmp_path, d), "--out", tmp_path / "out")
    assert code == 2 and "contacts[2].normal" in err, err
