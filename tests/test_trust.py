"""Answers that looked fine and were not: every one of them now said, or followed exactly."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import rbhyst
from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.errors import AnalysisError, InputError
from rbhyst.model.system import assemble
from rbhyst.model.settings import Settings
from rbhyst.solve.plan import prepare, simulate
from conftest import linear_set, seed_deck, square_linear_deck, write_deck


def run_cli(*args):
    res = CliRunner().invoke(app, [str(a) for a in args])
    return res.exit_code, res.stderr


def system_of(data, folder):
    return assemble(parse_deck(copy.deepcopy(data)), folder)


def shock_deck(signal: dict, dt: float, duration: float = 0.3) -> dict:
    data = square_linear_deck(k=2.0e5, mass=500.0)
    data["excitation"] = {"support": {"x1": signal}}
    data["analysis"] = {"dt": dt, "duration": duration}
    return data


# ------------------------------------------------------------------ excitation followed exactly


def test_an_analytic_pulse_shorter_than_dt_is_followed(tmp_path):
    """A 2 ms half-sine at dt = 5 ms: 0.1 rc gave exactly zero; now it gives the impulse's response,
    the same as the pulse sampled at 10 us in a file."""
    pulse = {"type": "half-sine", "amplitude": 20.0, "units": "g", "duration": 0.002, "start": 0.0123}
    analytic = simulate(system_of(shock_deck(pulse, 5e-3), tmp_path), Settings(dt=5e-3, duration=0.3))
    t = np.arange(0.0, 0.02 + 1e-12, 1e-5)  # the record spans the pulse: coarse steps after it, as analytic
    a = np.where((t >= 0.0123) & (t <= 0.0143), 20.0 * np.sin(np.pi * (t - 0.0123) / 0.002), 0.0)
    np.savetxt(tmp_path / "pulse.csv", np.column_stack([t, a]), delimiter=",", header="time_s,acc_g", comments="")
    sampled = simulate(system_of(shock_deck({"file": "pulse.csv", "units": "g"}, 5e-3), tmp_path),
                       Settings(dt=5e-3, duration=0.3))
    assert analytic.stats.record_substeps == math.ceil(5e-3 / (0.002 / 40))
    # the velocity change is the pulse's impulse (2/pi) A T, taken before the spring acts much
    dv = 2.0 / math.pi * 20.0 * 9.80665 * 0.002
    assert np.max(np.abs(analytic.v[:, 0])) == pytest.approx(dv, rel=0.02)
    peak = np.max(np.abs(sampled.d[:, 0]))
    assert np.max(np.abs(analytic.d[:, 0] - sampled.d[:, 0])) < 2e-3 * peak


def test_substeps_only_where_a_pulse_acts(tmp_path):
    """A short pulse splits the steps it spans, not the whole run."""
    pulse = {"type": "triangle", "amplitude": 5.0, "units": "g", "duration": 0.004, "start": 0.1}
    system = system_of(shock_deck(pulse, 1e-3, duration=2.0), tmp_path)
    plan = prepare(system, Settings(dt=1e-3, duration=2.0))
    # the pulse spans steps 100-103; one step more on either side
    assert plan.bounds.tolist() == [0, 99, 105, 2000] and plan.substeps.tolist() == [1, 10, 1]
    res = plan.run()
    assert res.stats.steps_taken == 2000 - 6 + 6 * 10


@pytest.mark.parametrize("kind, impulse", [("half-sine", 2 / math.pi), ("haversine", 0.5), ("triangle", 0.5),
                                           ("terminal-peak-sawtooth", 0.5)])
def test_pulse_shapes_carry_their_impulse(tmp_path, kind, impulse):
    """Each shape's velocity change on a free mass is amplitude x duration x its impulse factor."""
    data = shock_deck({"type": kind, "amplitude": 10.0, "units": "m/s2", "duration": 0.011, "start": 0.005}, 1e-3)
    data["hysteresis"]["lin"] = linear_set(1e-3)  # a nearly free body: the velocity change is the impulse
    res = simulate(system_of(data, tmp_path), Settings(dt=1e-3, duration=0.05))
    assert res.v[-1, 0] == pytest.approx(-impulse * 10.0 * 0.011, rel=2e-3)


# ------------------------------------------------------------------ peaks from every step


def test_peaks_come_from_every_step_whatever_every_keeps(tmp_path):
    data = seed_deck(duration=2.0)
    full = simulate(system_of(data, tmp_path), Settings(dt=1e-3, duration=2.0))
    sparse = simulate(system_of(data, tmp_path), Settings(dt=1e-3, duration=2.0, every=50))
    assert len(sparse.time) == 41
    assert sparse.extremes.peaks() == full.extremes.peaks()
    # ... whereas the written rows alone would have missed them
    assert np.max(np.abs(sparse.column("at1_m_s2"))) < 0.99 * full.extremes.peak("at1_m_s2")
    assert sparse.energy_balance == full.energy_balance


def test_extremes_match_the_columns_and_their_times(tmp_path):
    res = simulate(system_of(seed_deck(duration=1.0), tmp_path), Settings(dt=1e-3, duration=1.0))
    ex = res.extremes.as_dict()
    for name in ("u1_m", "at2_m_s2", "e3_f_N", "R3_Nm"):
        col = res.column(name)
        assert ex[name]["max"] == col.max() and ex[name]["min"] == col.min()
        assert ex[name]["time_of_max_s"] == res.time[np.argmax(col)]
        assert ex[name]["time_of_min_s"] == res.time[np.argmin(col)]


def test_the_resultant_equals_minus_m_times_the_total_acceleration(tmp_path):
    """Under support motion alone the mounts transmit R = -M at (eq. 11)."""
    res = simulate(system_of(seed_deck(duration=1.0), tmp_path), Settings(dt=1e-3, duration=1.0))
    m = res.system.mass
    r = np.column_stack([res.column(c) for c in ("R1_N", "R2_N", "R3_Nm")])
    np.testing.assert_allclose(r, -res.total_acceleration * m, atol=1e-9 * np.max(np.abs(r)))


# ------------------------------------------------------------------ warnings and notes


def summary(folder):
    return json.loads((folder / "summary.json").read_text())


def test_warnings_and_notes_reach_summary_json(tmp_path):
    data = seed_deck(duration=0.5)
    data["body"]["vertices"] = [[x + 1.0, y] for x, y in data["body"]["vertices"]]
    data["analysis"]["max_omega_dt"] = 0.05  # substeps: a note
    out = tmp_path / "o"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0, err
    s = summary(out)
    printed = [line[len("note: "):] for line in err.splitlines() if line.startswith("note: ")]
    assert printed and printed == s["notes"]
    assert any("substeps" in n for n in s["notes"]) and any("not centred" in n for n in s["notes"])
    assert s["warnings"] == [line[len("warning: "):] for line in err.splitlines() if line.startswith("warning: ")]


def test_large_rotations_are_warned(tmp_path):
    """A small body on soft elements pushed by a moment, with the seed's small rotations asked
    for: theta3 past 0.05 rad is said, with its size; left to "auto", the same deck takes exact
    kinematics and has nothing to say of them."""
    data = square_linear_deck(k=1.0e3, mass=10.0, side=0.2)
    data["excitation"] = {"force": {"m3": {"type": "sine", "amplitude": 20.0, "frequency_hz": 0.5,
                                           "units": "N m", "cycles": 0.5}}}
    out = tmp_path / "o"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0, err
    assert summary(out)["kinematics"]["model"] == "exact"
    assert not any("rotation" in w for w in summary(out)["warnings"])
    data["analysis"]["kinematics"] = "small"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0, err
    theta = summary(out)["peaks"]["theta3_rad"]
    assert theta > 0.05
    warning = [w for w in summary(out)["warnings"] if "rotation" in w]
    assert len(warning) == 1 and f"{theta:.3g} rad" in warning[0] and "eqs. 7-8" in warning[0]
    data["excitation"]["force"]["m3"]["amplitude"] = 1.0
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0 and not any("rotation" in w for w in summary(out)["warnings"])


@pytest.mark.parametrize("excitation, words", [
    (None, "the deck has no excitation"),
    ({"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 2.0, "units": "g", "start": 5.0}}},
     "no excitation acts within"),
])
def test_an_excitation_that_never_acts_is_warned(tmp_path, excitation, words):
    data = square_linear_deck()
    if excitation is not None:
        data["excitation"] = excitation
    out = tmp_path / "o"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0
    assert any(words in w for w in summary(out)["warnings"]) and "warning: " + words in err
    assert summary(out)["peaks"]["u1_m"] == 0.0


def test_a_force_without_point_acts_at_the_mass_centre_and_says_so(tmp_path):
    data = square_linear_deck()
    data["body"]["vertices"] = [[x + 2.0, y + 1.0] for x, y in data["body"]["vertices"]]
    data["elements"] = [dict(el, point=[el["point"][0] + 2.0, el["point"][1] + 1.0]) for el in data["elements"]]
    data["excitation"] = {"force": {"p1": {"type": "sine", "amplitude": 100.0, "frequency_hz": 3.0, "units": "N"}}}
    out = tmp_path / "o"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0
    assert any("act at the mass centre G (2, 1) m" in n for n in summary(out)["notes"])
    peaks = summary(out)["peaks"]  # through G: no moment, wherever the origin is
    assert peaks["theta3_rad"] * 0.5 < 1e-12 * peaks["u1_m"] and peaks["u1_m"] > 0


def test_implausible_geometry_gets_a_note_with_its_numbers(tmp_path):
    data = square_linear_deck(side=0.8)
    data["elements"].append({"point": [7.0, 0.0], "angle_deg": 90.0, "hysteresis": "lin"})
    system = system_of(data, tmp_path)
    assert any(n.startswith("elements[5]: attached at (7, 0) m, 7 m from the mass centre") for n in system.notes)
    mm = square_linear_deck(side=800.0)  # a body given in mm
    assert any("are the vertices in mm?" in n for n in system_of(mm, tmp_path).notes)


# ------------------------------------------------------------------ size and memory


def test_a_run_that_cannot_fit_the_disk_is_refused_before_anything_runs(tmp_path, monkeypatch):
    import shutil
    from collections import namedtuple

    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 2.0, "units": "g"}}}
    data["analysis"]["duration"] = 1.0e6
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(10**12, 0, 10**10))
    out = tmp_path / "o"
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"error: {out}: analysis.duration, analysis.dt, output.every: the run would write 1e+09 rows")
    assert "output.every = " in err and not out.exists()


def test_absurd_step_counts_are_refused(tmp_path):
    data = square_linear_deck()
    data["analysis"] = {"dt": 1e-6, "duration": 1.0e5}
    code, err = run_cli("run", write_deck(tmp_path, data), "--out", tmp_path / "o", "--no-plots")
    assert code == 2 and "beyond any analysis" in err and len(err.splitlines()) == 1


def test_the_api_keeps_no_more_rows_in_memory_than_it_can(tmp_path):
    data = square_linear_deck()
    data["analysis"] = {"dt": 1e-4, "duration": 1.0e5}
    deck = rbhyst.load_deck(write_deck(tmp_path, data))
    with pytest.raises(InputError, match=r"stream them to a folder instead \(rbhyst.run\(deck, out=...\)\)"):
        rbhyst.run(deck)


# ------------------------------------------------------------------ messages in the user's frame


def test_a_mechanism_is_named_in_the_decks_frame(tmp_path):
    data = square_linear_deck()
    data["body"]["vertices"] = [[x + 0.8, y + 0.7] for x, y in data["body"]["vertices"]]
    data["elements"] = [{"point": [1.3, 0.7], "angle_deg": 0.0, "hysteresis": "lin"},
                        {"point": [1.3, 0.7], "angle_deg": 90.0, "hysteresis": "lin"}]
    with pytest.raises(InputError, match=r"rotation about the point \(1.3, 0.7\) m$"):
        system_of(data, tmp_path)


def test_an_over_stiff_body_is_told_the_dt_that_would_work(tmp_path):
    data = square_linear_deck(k=1.0e12, mass=1.0)
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 1.0, "frequency_hz": 1.0, "units": "g"}}}
    with pytest.raises(AnalysisError, match=r"dt = [0-9.e-]+ s would do"):
        prepare(system_of(data, tmp_path), Settings(dt=1e-2, duration=1.0, max_substep_level=4))
