"""Stops (rbhyst.model.stop): a body launched against a stop rebounds as Walton and Braun's law says
in closed form, the contact never pulls, the energy balance closes with the impacts, the
fixed-step methods converge to the adaptive answer, and a stop never reached changes nothing."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from conftest import invoke, square_linear_deck, write_deck

from rbhyst import api
from rbhyst.model.deck import parse_deck

M, K_SPRING, K_STOP, E, GAP = 100.0, 1000.0, 1.0e6, 0.7, 0.005
FIXED = ("newmark", "central-difference", "chang", "kr-alpha")


def launched(integrator: str, dt: float, k_stop: float = K_STOP, space: bool = False) -> dict:
    """A square body on four weak linear springs (each K_SPRING), launched along x1 by a
    half-sine force at G; the two x1 springs bear on stops GAP beyond rest (each k_stop, E).
    ``space``: the same body as a box in space, its x1 springs as the plane's (x3 held by two more)."""
    d = square_linear_deck(k=K_SPRING, mass=M)
    if space:
        d["body"] = {"box": {"size": [1.0, 1.0, 1.0]}, "mass": M}
        lin = [{"point": p, "direction": v, "hysteresis": "lin"} for p, v in (
            ([0.0, 0.5, 0.0], [1.0, 0.0, 0.0]), ([0.0, -0.5, 0.0], [1.0, 0.0, 0.0]),
            ([0.5, 0.0, 0.0], [0.0, 1.0, 0.0]), ([-0.5, 0.0, 0.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, 0.5], [0.0, 1.0, 0.0]), ([0.0, 0.0, -0.5], [0.0, 1.0, 0.0]),
            ([0.5, 0.0, 0.0], [0.0, 0.0, 1.0]), ([-0.5, 0.0, 0.0], [0.0, 0.0, 1.0]),
            ([0.0, 0.5, 0.0], [0.0, 0.0, 1.0]), ([0.0, -0.5, 0.0], [0.0, 0.0, 1.0]))]
        d["elements"] = lin
    d["excitation"] = {"force": {"p1": {"type": "half-sine", "amplitude": 200.0, "duration": 0.05, "units": "N"}}}
    for el in d["elements"][:2]:
        el["stop"] = {"gap": GAP, "stiffness": k_stop, "restitution": E}
    d["analysis"] = {"dt": dt, "duration": 0.25, "integrator": integrator}
    return d


def closed_form(e_in: float, k_stop: float = K_STOP) -> tuple[float, float]:
    """(velocity ratio out / in at the gap, energy lost) of the launched body's first impact, from
    the energy the pulse put in: free (the pulse is over) it reaches the gap with 0.5 M v^2 =
    E_in - K_SPRING GAP^2 (two springs), loads both stops to d_max where 0.5 M v^2 = K_SPRING
    ((GAP + d)^2 - GAP^2) + k_stop d^2, and each loses 0.5 k_stop d_max^2 (1 - E^2)."""
    kin = e_in - K_SPRING * GAP**2
    a, b, c = K_SPRING + k_stop, 2.0 * K_SPRING * GAP, -kin
    dm = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    lost = k_stop * dm**2 * (1.0 - E * E)
    return float(np.sqrt((kin - lost) / kin)), float(lost)


def gap_velocities(result) -> list[float]:
    """v1 where u1 crosses GAP, linear between the rows."""
    u, v = result.column("u1_m"), result.column("v1_m_s")
    out = []
    for i in np.nonzero((u[:-1] - GAP) * (u[1:] - GAP) < 0.0)[0]:
        w = (GAP - u[i]) / (u[i + 1] - u[i])
        out.append(v[i] + w * (v[i + 1] - v[i]))
    return out


def run(data: dict):
    return api.run(parse_deck(data), estimate=False)


@pytest.mark.parametrize("integrator", FIXED + ("reference",))
def test_a_body_rebounds_with_the_restitution_and_loses_the_closed_form_energy(integrator):
    r = run(launched(integrator, 1e-4))
    e_in = float(r.column("E_input_J")[-1])
    ratio, lost = closed_form(e_in)
    v = gap_velocities(r)
    assert len(v) == 2 and v[0] > 0.0 > v[1]  # in, and out once (the spring is too weak to bring it back)
    assert -v[1] / v[0] == pytest.approx(ratio, rel=1e-3)
    assert ratio == pytest.approx(E, rel=0.05)  # free flight: the stop's restitution
    assert r.impact_energy == pytest.approx(lost, rel=1e-6 if integrator == "reference" else 1e-3)
    assert r.energy_balance < 1e-3
    s = r.summary()
    stop = s["elements"][0]["stop"]
    assert stop["impacts"] == 1 and stop["gap_m"] == [-GAP, GAP]
    assert stop["impact_J"] == pytest.approx(lost / 2, rel=1e-3)
    assert s["energy"]["impact_J"] == pytest.approx(r.impact_energy)
    assert "stop" not in s["elements"][2]


def test_the_contact_force_never_pulls_and_is_zero_within_the_gap():
    r = run(launched("newmark", 1e-4))
    u, f = r.column("e1_u_m"), r.column("e1_f_N")
    contact = f - K_SPRING * u  # the element's force beyond its linear spring's
    scale = float(np.max(np.abs(contact)))
    assert scale > 100.0  # it did bear
    assert np.all(contact >= -1e-9 * scale)
    assert np.all(np.abs(contact[u <= GAP]) <= 1e-9 * scale)


def test_fixed_step_methods_converge_to_the_adaptive_answer_on_a_stiff_stop():
    """A stop 100 times stiffer: the monitor splits steps at dt = 4e-4 (it resolves K / e^2);
    with dt / 8 the energy balance closes at least 8 times better and the impact's energy agrees
    with the adaptive solution's within 0.2 %."""
    ref = run(launched("reference", 4e-4, k_stop=1e8))
    for integrator in ("newmark", "central-difference", "kr-alpha"):
        coarse = run(launched(integrator, 4e-4, k_stop=1e8))
        fine = run(launched(integrator, 5e-5, k_stop=1e8))
        assert coarse.stats.substeps > 0, integrator
        assert fine.energy_balance < coarse.energy_balance / 8, integrator
        assert fine.impact_energy == pytest.approx(ref.impact_energy, rel=2e-3), integrator
    assert ref.energy_balance < 1e-6


def test_a_body_in_space_rebounds_as_in_the_plane():
    plane = run(launched("newmark", 1e-4))
    space = run(launched("newmark", 1e-4, space=True))
    ratio, lost = closed_form(float(space.column("E_input_J")[-1]))
    v = gap_velocities(space)
    assert -v[1] / v[0] == pytest.approx(ratio, rel=1e-3)
    assert space.impact_energy == pytest.approx(lost, rel=1e-3)
    assert space.impact_energy == pytest.approx(plane.impact_energy, rel=1e-9)
    ref = run(launched("reference", 1e-4, space=True))
    assert ref.impact_energy == pytest.approx(lost, rel=1e-6)


def test_a_stop_never_reached_changes_no_output_file(tmp_path):
    """The seed's scene with stops far beyond its deformations writes time_history.csv to the byte
    as without them (summary.json echoes the deck, so it says the stops)."""
    from conftest import seed_deck

    plain = seed_deck(duration=1.0)
    stopped = copy.deepcopy(plain)
    for el in stopped["elements"]:
        el["stop"] = {"gap": [-0.5, 0.4], "stiffness": 1e7, "restitution": 0.5}
    outs = []
    for name, d in (("plain", plain), ("stopped", stopped)):
        out = tmp_path / name
        api.run(parse_deck(d), out=out, plots=False)
        outs.append({p.name: p.read_bytes() for p in out.iterdir() if p.suffix == ".csv"})
    assert outs[0] and outs[0] == outs[1]
    assert "time_history.csv" in outs[0]


def test_a_stroke_with_a_stop_says_so():
    d = launched("newmark", 1e-4)
    for el in d["elements"][:2]:
        el["stroke"] = 0.004
    r = api.run(parse_deck(d), estimate=False)
    said = [w for w in r.warnings if "beyond its stroke" in w]
    assert said and all("stop at [-0.005, 0.005] m (beyond the stroke)" in w for w in said)


@pytest.mark.parametrize("stop, key, words", [
    ({"gap": 0.01, "stiffness": 1e6, "restitution": 0.0}, "elements[1].stop.restitution", "greater than 0"),
    ({"gap": 0.01, "stiffness": 1e6, "restitution": 1.5}, "elements[1].stop.restitution", "less than or equal to 1"),
    ({"gap": [0.01, 0.02], "stiffness": 1e6, "restitution": 0.5}, "elements[1].stop.gap", "lower < 0 < upper"),
    ({"gap": 0.01, "stiffness": -1.0, "restitution": 0.5}, "elements[1].stop.stiffness", ""),
    ({"gap": 0.01, "stiffness": 1e6, "e": 0.5}, "elements[1].stop", ""),
])
def test_a_bad_stop_is_one_line_naming_its_key(tmp_path, stop, key, words):
    d = square_linear_deck()
    d["elements"][0]["stop"] = stop
    code, err = invoke("run", write_deck(tmp_path, d), "--out", tmp_path / "out")
    assert code == 2
    lines = [ln for ln in err.splitlines() if key in ln]
    assert lines and words in lines[0], err
    assert "Traceback" not in err


def test_the_console_names_the_stops_struck_and_those_never_reached():
    from rbhyst.report.console import stop_lines

    d = launched("newmark", 1e-4)
    d["elements"][2]["stop"] = {"gap": 0.5, "stiffness": 1e6, "restitution": 0.5}
    lines = stop_lines(run(d).summary())
    assert len(lines) == 2
    assert lines[0].startswith("stops struck: e1: 1 impact, peak ") and "; e2: 1 impact" in lines[0]
    assert lines[1] == "stops never reached: e3"


def test_the_shipboard_sample_strikes_its_snubbers_and_runs_clean():
    """decks/shipboard_cabinet_shock.toml: MSS isolators whose axial directions bottom out on
    snubbers; its shock drives them in, and the impacts raise the peak acceleration at G well above
    that of the same cabinet with its snubbers out of reach."""
    from conftest import DECKS

    from rbhyst.model.deck import load_deck

    deck = load_deck(DECKS / "shipboard_cabinet_shock.toml")
    r = api.run(deck)
    assert r.warnings == []
    axial = [e for e in r.summary()["elements"] if e.get("role") == "axial"]
    assert len(axial) == 4 and all(e["stop"]["impacts"] >= 1 for e in axial)
    clear = deck.with_values({f"isolators[{k}].stop.axial.gap": 0.05 for k in range(1, 5)})
    free = api.run(clear, estimate=False)
    assert free.summary()["elements"][0]["stop"]["impacts"] == 0
    assert free.extremes.peak("at3_m_s2") < 0.7 * r.extremes.peak("at3_m_s2")
