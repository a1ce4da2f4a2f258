"""``rbhyst shock``: a deck along each direction of each axis under a classical pulse, its demands
those of each run's summary, a linear body's peak that of its oscillator's shock spectrum, and
its verdict's exit status."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import invoke, linear_set, write_deck

from rbhyst.analyses.shock.drive import G
from rbhyst.model.shock_pulses import classical_pulse
from rbhyst.solve.shock_spectra import shock_spectrum

MASS, K, C = 1000.0, 1.0e5, 4000.0


def box(limit_g: float = 30.0, **shock) -> dict:
    """A 1 m square of 1000 kg on two vertical linear springs of K at its bottom corners, two
    horizontal ones at its mid-sides and a vertical damper at G: vertically an oscillator of
    2 K, damping C (no rotation: the springs and the damper are symmetric about G)."""
    return {
        "body": {"vertices": [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]], "mass": MASS},
        "hysteresis": {"lin": linear_set(K)},
        "elements": [{"vertex": 1, "angle_deg": 90.0, "hysteresis": "lin", "stroke": 0.2},
                     {"vertex": 2, "angle_deg": 90.0, "hysteresis": "lin", "stroke": 0.2},
                     {"point": [0.0, 0.5], "angle_deg": 0.0, "hysteresis": "lin"},
                     {"point": [0.0, -0.5], "angle_deg": 0.0, "hysteresis": "lin"}],
        "dampers": [{"point": [0.0, 0.0], "angle_deg": 90.0, "c": C}],
        "analysis": {"dt": 0.001},
        "output": {"points": [{"name": "top", "point": [0.5, 0.5]}]},
        "shock": {"pulse": "810c-basic-design", "axes": ["x2"], "shocks": 1,
                  "acceleration_limit_g": {"G": limit_g}, "force_capacity_N": 1.0e6, **shock},
    }



def demands_are_each_runs(q: dict, out) -> dict:
    """Every criterion of qualification.json ``q`` (in folder ``out``) has a value for each run,
    equal to that run's summary.json peak, and the largest as its demand; the worst is the least
    margin's. Returns that criterion."""
    summaries = {r["run"]: json.loads((out / r["summary"]).read_text()) for r in q["runs"]}
    for c in q["criteria"]:
        assert set(c["per_run"]) == set(summaries)
        for run, value in c["per_run"].items():
            if c["criterion"] == "acceleration":
                assert value == summaries[run]["peaks"][c["column"]] / G
            elif c["criterion"] == "force":
                assert value == summaries[run]["peaks"][c["column"]]
        assert c["demand"] == max(c["per_run"].values())
    worst = min(q["criteria"], key=lambda c: c["margin"])
    assert (q["worst"]["margin"], q["worst"]["run"]) == (worst["margin"], worst["worst_run"])
    return worst

def test_the_demands_are_each_runs_and_a_linear_body_peaks_at_its_spectrum(tmp_path):
    out = tmp_path / "o"
    code, err = invoke("shock", write_deck(tmp_path, box()), "--out", out, "--no-plots")
    assert code == 0, err
    data = json.loads((out / "shock.json").read_text())
    assert [r["run"] for r in data["runs"]] == ["x2+", "x2-"]
    summaries = {r["run"]: json.loads((out / r["summary"]).read_text()) for r in data["runs"]}
    for c in data["criteria"]:
        for run, value in c["per_run"].items():
            s = summaries[run]
            if c["criterion"] == "acceleration":
                assert value == s["peaks"][c["column"]] / G
            elif c["criterion"] == "force":
                assert value == s["peaks"][c["column"]]
        assert c["demand"] == max(c["per_run"].values())
        assert c["worst_run"] in c["per_run"] and c["per_run"][c["worst_run"]] == c["demand"]
    # vertically the box is an oscillator of 2 K and C: G's peak total acceleration is the maximax of
    # that oscillator's shock spectrum under the drive (15 g 11 ms half-sine, bare)
    zeta = C / (2.0 * math.sqrt(2.0 * K * MASS))
    f = math.sqrt(2.0 * K / MASS) / (2.0 * math.pi)
    p = classical_pulse("half-sine", 15.0 * G, 0.011)
    want = shock_spectrum(p.series.values, p.series.dt, [f], [zeta]).maximax[0, 0] / G
    got = next(c for c in data["criteria"] if c["item"] == "G x2")
    assert got["per_run"]["x2+"] == pytest.approx(want, rel=1e-4)
    # a linear body answers the reversed shock with the reversed motion
    assert got["per_run"]["x2-"] == pytest.approx(got["per_run"]["x2+"], rel=1e-9)
    assert data["drive"]["tolerance"]["pass"] and data["pass"]
    assert data["worst"]["run"] in ("x2+", "x2-")


def test_a_limit_exceeded_fails_and_repeated_shocks_of_a_linear_body_agree(tmp_path):
    out = tmp_path / "o"
    # (at dt = 0.2 ms: each shock's own peaks are over the rows, which at 1 ms miss 0.3 % of this one)
    code, err = invoke("shock", write_deck(tmp_path, box(limit_g=0.2, compensation="pre-post", shocks=2)),
                       "--out", out, "--no-plots", "--dt", "0.0002")
    assert code == 1, err
    assert "fail: acceleration G x2:" in err and "verdict: fail" in err
    data = json.loads((out / "shock.json").read_text())
    assert data["drive"]["pulse"]["compensation"] == "pre-post"
    assert abs(data["drive"]["table"]["end_velocity_m_s"]) < 1e-12
    for run in data["runs"]:
        first, second = run["shocks"]
        # the free vibration of the first has decayed (e^-(zeta w t) over the rest between them)
        assert second["largest_change_from_the_first"] < 1e-3
        assert first["from_s"] == 0.0 and second["from_s"] > 2.0


@pytest.mark.parametrize("extra, args, said", [
    ({"pulse": None}, [], "shock: no shock"),
    ({"pulse": "mil-std-999"}, [], "shock.pulse: 'mil-std-999' is not a pulse rbhyst knows"),
    ({}, ["--pulse", "nope"], "--pulse: 'nope' is not a pulse rbhyst knows"),
    ({}, ["--axes", "x3"], "--axes: 'x3': an axis of the deck (x1, x2)"),
    ({}, ["--record", "r.csv", "--pulse", "810c-basic-design"], "--record: not with --pulse"),
    ({}, ["--record", "r.csv"], "--units: the units of --record's values"),
    ({}, ["--record", "r.csv", "--units", "g", "--compensation", "pre-post"], "--compensation: only with a named"),
    ({"acceleration_limit_g": {"nowhere": 3.0}}, [], "shock.acceleration_limit_g.nowhere: no point"),
    ({"pulse": {"type": "half-sine", "amplitude": 10, "units": "g", "duration": 0.01, "start": 0.1}}, [],
     "shock.pulse.start: a shock test's pulse starts at 0 s"),
])
def test_shock_mistakes(tmp_path, extra, args, said):
    data = box()
    data["shock"].update(extra)
    data["shock"] = {k: v for k, v in data["shock"].items() if v is not None}
    code, err = invoke("shock", write_deck(tmp_path, data), "--out", tmp_path / "o", *args)
    assert code == 2 and said in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_a_record_drive_and_its_plots(tmp_path):
    t = np.arange(0, 401) * 2.5e-5
    acc = np.where(t <= 0.01, 10.0 * np.sin(np.pi * t / 0.01), 0.0)
    rec = tmp_path / "r.csv"
    np.savetxt(rec, np.column_stack([t, acc]), delimiter=",", header="time_s,acceleration_g", comments="")
    data = box()
    del data["shock"]["pulse"]
    out = tmp_path / "o"
    code, err = invoke("shock", write_deck(tmp_path, data), "--record", rec, "--units", "g", "--out", out)
    assert code == 0, err
    facts = json.loads((out / "shock.json").read_text())["drive"]
    assert facts["source"] == "the record r.csv" and facts["peak_g"] == pytest.approx(10.0)
    assert (out / "srs.png").exists() and (out / "pvss.png").exists() and not (out / "pulse.png").exists()
    # its report: the figures embedded, the record among the files it was made from
    code, err = invoke("report", out)
    assert code == 0, err
    text = (out / "report.html").read_text()
    assert 'data-file="srs.png"' in text and 'data-file="pvss.png"' in text
    inputs = json.loads((out / "shock.json").read_text())["provenance"]["inputs"]
    assert [i["key"] for i in inputs] == ["deck", "--record"] and str(rec) in text


def test_the_sample_deck_asks_for_procedure_one():
    from conftest import DECKS

    from rbhyst.analyses.shock.verdict import request, run_labels
    from rbhyst.model.deck import load_deck

    req = request(load_deck(DECKS / "electronics_shock.toml"), {})
    assert req.pulse[:4] == ("terminal-peak-sawtooth", 20.0 * G, 0.011, "pre-post")
    assert req.shocks == 3 and run_labels(req) == ["x1+", "x1-", "x2+", "x2-"]
    assert req.acceleration_limit_g == {"top": 15.0, "G": 12.0}


def qualify_box(tmp_path, **shock) -> dict:
    """box() with its limits and shock under [qualify] (an SRS specification from 100 Hz up)."""
    (tmp_path / "spec.csv").write_text("frequency_hz,srs_g\n100,10\n400,30\n1000,30\n")
    data = box()
    own = data.pop("shock")
    data["qualify"] = {"acceleration_limit_g": own["acceleration_limit_g"], "force_capacity_N": 1.0e6,
                       "shock": {"srs": "spec.csv", **shock}}
    return data


def test_qualify_shock_runs_each_axis_both_ways_and_its_demands_are_each_runs(tmp_path):
    out = tmp_path / "q"
    deck = write_deck(tmp_path, qualify_box(tmp_path, shocks=2))
    code, err = invoke("qualify", deck, "--out", out, "--no-plots")
    assert code in (0, 1), err
    q = json.loads((out / "qualification.json").read_text())
    data = json.loads((out / "shock.json").read_text())
    assert q["kind"] == "shock" and q["details"] == "shock.json" and q["pass"] == data["pass"]
    # every axis of the deck, both directions, the deck's number of shocks in each: 2 x 2 x 2 = 8
    assert [r["run"] for r in q["runs"]] == ["x1+", "x1-", "x2+", "x2-"]
    assert sum(len(r["shocks"]) for r in data["runs"]) == 8
    demands_are_each_runs(q, out)
    # report.html of the folder: every number it shows with its source in shock.json is that value
    import re

    code, err = invoke("report", out)
    assert code == 0, err
    text = (out / "report.html").read_text()
    assert "Shock verdict" in text and q["provenance"]["inputs"][1]["file"] == "spec.csv"
    shown = re.findall(r'data-src="shock\.json:([^"]+)" data-value="([^"]+)"', text)
    assert len(shown) > 3 * len(data["criteria"])
    for path, value in shown:
        node = data
        for part in path.split("."):
            node = node[int(part)] if isinstance(node, list) else node[part]
        assert float(value) == node, path
    # each axis its own drive, matched to the specification, the one make-shock makes for that axis
    assert data["drive"]["within"] is True
    code, err = invoke("make-shock", tmp_path / "m", "--srs", tmp_path / "spec.csv", "--axes", 3, "--no-plots")
    assert code == 0, err

    def values(path):
        return [line.split(",")[1] for line in path.read_text().splitlines()[2:]]

    made = values(tmp_path / "m" / "shock_x1.csv")
    assert np.allclose(np.array(values(out / "drive_x1.csv"), float)[:len(made)], np.array(made, float), rtol=1e-9)
    # the plane's vertical x2 is make-shock's vertical x3 (the same stream)
    made = values(tmp_path / "m" / "shock_x3.csv")
    assert np.allclose(np.array(values(out / "drive_x2.csv"), float)[:len(made)], np.array(made, float), rtol=1e-9)


@pytest.mark.parametrize("args, said", [
    (("--pulse", "nope"), "--pulse: 'nope' is not a pulse"),
    (("--pulse", "810c-basic-design", "--standard", "ac156"), "--standard: not with a shock qualification"),
])
def test_qualify_shock_mistakes(tmp_path, args, said):
    deck = write_deck(tmp_path, qualify_box(tmp_path))
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", *args)
    assert code == 2 and said in err, err


def test_qualify_pulse_is_the_shock_commands_verdict(tmp_path):
    data = box()
    own = data.pop("shock")
    data["qualify"] = {"acceleration_limit_g": own["acceleration_limit_g"], "force_capacity_N": 1.0e6,
                       "shock": {"axes": ["x2"], "shocks": 1}}
    deck = write_deck(tmp_path, data)
    code, err = invoke("qualify", deck, "--pulse", "810c-basic-design", "--out", tmp_path / "q", "--no-plots")
    assert code == 0, err
    code, err = invoke("shock", write_deck(tmp_path, box(), name="own"), "--out", tmp_path / "s", "--no-plots")
    assert code == 0, err
    a, b = (json.loads((tmp_path / d / "shock.json").read_text()) for d in ("q", "s"))
    assert [c["demand"] for c in a["criteria"]] == [c["demand"] for c in b["criteria"]]


def test_the_shipboard_sample_deck_runs_18_shocks_names_the_worst_and_its_demands_are_each_runs(tmp_path):
    from conftest import DECKS

    out = tmp_path / "q"
    code, err = invoke("qualify", DECKS / "electronics_shipboard.toml", "--out", out, "--no-plots")
    assert code == 1, err  # it fails on purpose: the box's vertical mode sits on the SRS's ramp
    q = json.loads((out / "qualification.json").read_text())
    data = json.loads((out / "shock.json").read_text())
    assert [r["run"] for r in q["runs"]] == ["x1+", "x1-", "x2+", "x2-", "x3+", "x3-"]
    assert sum(len(r["shocks"]) for r in data["runs"]) == 18
    worst = demands_are_each_runs(q, out)
    assert f"least margin {worst['margin']:.3g} ({q['worst']['criterion']}, run {worst['worst_run']})" in err
    assert data["drive"]["within"] is True and sorted(data["drive"]["per_axis"]) == ["x1", "x2", "x3"]
