"""The analyses built on runs, for a deck in space (docs/explanation/space.md): qualification in three
axes (x1, x2 horizontal, x3 vertical), transmissibility along x1, x2 or x3, the study of six
coordinates and sweeps whose motions carry x3. A prism extruded from a plane body reproduces the
plane command's numbers for the in-plane quantities; a motion along x3 gives the vertical responses;
mistakes are one line each, exit 2."""

from __future__ import annotations

import copy
import csv
import json
import math

import numpy as np
import pytest

import rbhyst
from conftest import DECKS, TABLE3_AXIAL, TABLE3_SHEAR, invoke, linear_set, write_deck
from test_body3d import plane_and_prism

G = 9.80665


def errors(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("error:")]


def read_csv(path) -> list[dict]:
    with open(path) as fh:
        return list(csv.DictReader(fh))


# ------------------------------------------------------------------ qualification


def upright_cabinet() -> dict:
    """A plane cabinet (x1 horizontal, x2 vertical) on two pairs of isolators with strokes, a
    point at its top and a [qualify]."""
    return {
        "title": "upright cabinet",
        "body": {"vertices": [[0.0, 0.0], [0.8, 0.0], [0.8, 2.0], [0.0, 2.0]], "mass": 550.0},
        "hysteresis": {"wri_axial": copy.deepcopy(TABLE3_AXIAL), "wri_shear": copy.deepcopy(TABLE3_SHEAR)},
        "elements": [{"vertex": v, "angle_deg": a, "hysteresis": h, "count": 2, "stroke": 0.05}
                     for v in (1, 2) for a, h in ((270.0, "wri_axial"), (0.0, "wri_shear"))],
        "analysis": {"dt": 0.001, "integrator": "chang"},
        "output": {"points": [{"name": "top", "point": [0.4, 2.0]}]},
        "qualify": {"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "seed": 2,
                    "acceleration_limit_g": {"top": 3.0, "G": [2.0, 1.5]}, "force_capacity_N": 20000.0},
    }


def upright_prism(plane: dict) -> dict:
    """The same cabinet in space, its plane the x1-x3 plane (x3 vertical): a box 0.6 m deep
    along x2, symmetric about the plane (J22 the plane's J), the plane's elements at their points
    along their directions in x1-x3, and four linear springs along x2 holding u2, theta1 and
    theta3 without touching the plane motion (u1, u3, theta2 = -theta3 of the plane)."""
    prism = copy.deepcopy(plane)
    prism["body"] = {"box": {"size": [0.8, 0.6, 2.0], "centre": [0.4, 0.0, 1.0]}, "mass": 550.0}
    prism["hysteresis"]["across"] = linear_set(2.0e5)
    corners = {1: (0.0, 0.0), 2: (0.8, 0.0)}
    elements = []
    for el in plane["elements"]:
        x, z = corners[el["vertex"]]
        a = math.radians(el["angle_deg"])
        elements.append({"point": [x, 0.0, z], "direction": [round(math.cos(a), 15), 0.0, round(math.sin(a), 15)],
                         "hysteresis": el["hysteresis"], "count": el["count"], "stroke": el["stroke"]})
    for dx, dz in ((0.3, 0.4), (-0.3, 0.4), (-0.3, -0.4), (0.3, -0.4)):
        elements.append({"point": [0.4 + dx, 0.0, 1.0 + dz], "direction": [0.0, 1.0, 0.0], "hysteresis": "across"})
    prism["elements"] = elements
    prism["output"] = {"points": [{"name": "top", "point": [0.4, 0.0, 2.0]}]}
    prism["qualify"]["acceleration_limit_g"] = {"top": 3.0, "G": [2.0, 2.0, 1.5]}
    return prism


@pytest.fixture(scope="module")
def qualified(tmp_path_factory):
    """The plane cabinet and its prism qualified to AC156, one motion each, same seed."""
    tmp = tmp_path_factory.mktemp("qualify")
    plane = upright_cabinet()
    out = {}
    for name, data in (("plane", plane), ("prism", upright_prism(plane))):
        code, err = invoke("qualify", write_deck(tmp, data, name), "--out", tmp / name)
        out[name] = (code, err, json.loads((tmp / name / "qualification.json").read_text()), tmp / name)
    return out


def test_a_prism_qualified_in_space_reproduces_the_plane_verdict_in_its_plane(qualified):
    _, _, flat, flat_dir = qualified["plane"]
    code, err, solid, solid_dir = qualified["prism"]
    assert solid["axes"] == {"x1": "horizontal", "x2": "horizontal", "x3": "vertical"}
    assert flat["axes"] == {"x1": "horizontal", "x2": "vertical"}
    # the horizontal RRS drives x1 and x2, the vertical x3; x1 and the vertical have the plane's noise
    assert solid["rrs"]["x1"] == solid["rrs"]["x2"] == flat["rrs"]["x1"] and solid["rrs"]["x3"] == flat["rrs"]["x2"]

    def rows(path):
        return [line for line in path.read_text().splitlines() if not line.startswith("#")]

    assert rows(solid_dir / "motions" / "m1_x1.csv") == rows(flat_dir / "motions" / "m1_x1.csv")
    assert rows(solid_dir / "motions" / "m1_x3.csv") == rows(flat_dir / "motions" / "m1_x2.csv")
    assert rows(solid_dir / "motions" / "m1_x2.csv") != rows(flat_dir / "motions" / "m1_x1.csv")
    assert (solid_dir / "motions" / "m1_x3.csv").read_text().startswith("# rbhyst qualify prism.toml: motion 1, "
                                                                          "x3 (vertical)")
    # every in-plane criterion has the plane's demand: strokes, G and the top along x1 and the
    # vertical (x2 there, x3 here), the plane's elements' forces
    def label(c):
        return f"{c['criterion']} {c['item']}"

    same = {label(c).replace(" x2", " x3") if c["criterion"] == "acceleration" else label(c): c
            for c in flat["criteria"]}
    mine = {label(c): c for c in solid["criteria"]}
    assert len(same) == 4 + 4 + 8 and len(mine) == 4 + 6 + 12
    for label, c in same.items():
        assert mine[label]["demand"] == pytest.approx(c["demand"], rel=1e-9, abs=1e-12), label
        column = c["column"].replace("at2", "at3") if c["criterion"] == "acceleration" else c["column"]
        assert mine[label]["capacity"] == c["capacity"] and mine[label]["column"] == column
    # the horizontal x2 motion moves the prism across its plane
    assert mine["acceleration top x2"]["demand"] > 0.1 and mine["acceleration G x2"]["column"] == "at2_m_s2"
    assert mine["acceleration top x3"]["column"] == "top_at3_m_s2"
    correlations = solid["motions"][0]["correlations"]
    assert set(correlations) == {"x1_x2", "x1_x3", "x2_x3"} and max(map(abs, correlations.values())) < 0.3
    assert solid["motions"][0]["correlation_x1_x2"] == correlations["x1_x2"]
    assert "correlations" not in flat["motions"][0]
    assert [r[:2] for r in (line.split(",") for line in (solid_dir / "trs.csv").read_text().splitlines()[1:])
            ][::30] == [["1", "x1"], ["1", "x2"], ["1", "x3"]]
    assert (code == 0) == solid["pass"] and err.splitlines()[-1] == f"wrote {solid_dir}"


def test_the_plane_verdict_keeps_its_files_and_keys(qualified):
    code, err, flat, out = qualified["plane"]
    assert sorted(p.name for p in (out / "motions").iterdir()) == ["m1_x1.csv", "m1_x2.csv"]
    assert set(flat["trs"]["band"]) == {"x1", "x2"} and [c["item"] for c in flat["criteria"]][4:8] == [
        "top x1", "top x2", "G x1", "G x2"]
    assert (out / "qualification.png").exists() and (qualified["prism"][3] / "qualification.png").exists()


def test_rrs_files_in_space_drive_x1_and_x2_with_rrs_and_x3_with_rrs_x3(tmp_path):
    from rbhyst.analyses.qualification.rrs import requested_rrs

    h, v = tmp_path / "h.csv", tmp_path / "v.csv"
    h.write_text("frequency_hz,sa_g\n1.0,1.0\n30.0,0.5\n")
    v.write_text("frequency_hz,sa_g\n1.0,0.5\n30.0,0.25\n")
    keys = {"rrs": "--rrs", "rrs_x2": "--rrs-x2", "rrs_x3": "--rrs-x3", "damping": "--rrs-damping", "sds": "--sds",
            "z_over_h": "--z-over-h", "level": "--level"}
    rrs, standard = requested_rrs(str(h), None, 0.05, None, None, tmp_path, keys, rrs_x3=str(v), space=True)
    assert standard is None and list(rrs) == ["x1", "x2", "x3"]
    assert rrs["x2"](10.0) == rrs["x1"](10.0) and rrs["x3"](10.0) == pytest.approx(0.5 * rrs["x1"](10.0))
    rrs, _ = requested_rrs(str(h), str(v), 0.05, None, None, tmp_path, keys, space=True)
    assert list(rrs) == ["x1", "x2"] and rrs["x2"](10.0) == pytest.approx(0.5 * rrs["x1"](10.0))
    rrs, _ = requested_rrs("ieee693", None, None, None, None, tmp_path, keys, level="high", space=True)
    assert [r.source for r in rrs.values()] == ["IEEE Std 693-2005, Figure A.1"] * 2 + [
        "IEEE Std 693-2005, Figure A.1, vertical 80 %"]


def _sample_with(tmp_path, qualify: dict, **changes) -> object:
    data = rbhyst.load_deck(DECKS / "cabinet_3d.toml").model_dump(mode="python", exclude_unset=True)
    for axis in ("x1", "x2", "x3"):
        data["excitation"]["support"][axis]["file"] = str(DECKS / data["excitation"]["support"][axis]["file"])
    data.pop("output", None)
    data["output"] = {"points": [{"name": "top1", "point": [0.0, 0.0, 2.0]}]}
    data["qualify"] = qualify
    for key, value in changes.items():
        data[key] = value
    return write_deck(tmp_path, data, "space")


@pytest.mark.parametrize("qualify, options, lines", [
    ({"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "acceleration_limit_g": {"G": [2.0, 1.5]}}, [],
     ["qualify.acceleration_limit_g.G: 2 values: one number for every direction or [x1, x2, x3] (the deck is in "
      "space)"]),
    ({"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "force_capacity_N": 1e4}, ["--rrs-x3", "v.csv"],
     ["--rrs-x3: not with qualify.standard ac156: the standard gives it"]),
    ({"force_capacity_N": 1e4}, ["--rrs", "{tmp}/h.csv"],  # (x1 and x2 read it: its problem said once)
     ["rrs_damping: required with an RRS file: the damping ratio it is drawn for (0.05 for 5 %)"]),
])
def test_qualify_mistakes_in_space_are_one_line_each(tmp_path, qualify, options, lines):
    deck = _sample_with(tmp_path, qualify)
    (tmp_path / "h.csv").write_text("frequency_hz,sa_g\n1.0,1.0\n30.0,0.5\n")
    options = [o.format(tmp=tmp_path) for o in options]
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", *options)
    found = errors(err)
    assert code == 2 and len(found) == len(lines), err
    for got, want in zip(found, lines):
        assert want.format(tmp=tmp_path) in got, (got, want)
    assert not (tmp_path / "q").exists()


def test_qualify_mistakes_name_the_axis_the_deck_has(tmp_path):
    deck = _sample_with(tmp_path, {"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "force_capacity_N": 1e4},
                        body={"box": {"size": [0.8, 0.6, 2.0], "centre": [0.4, 0.3, 1.0]}, "mass": 550.0,
                              "gravity": [0.0, -9.80665, 0.0]})
    code, err = invoke("qualify", deck, "--out", tmp_path / "q")
    assert code == 2 and errors(err) == [
        "error: body.gravity: acts along x2, but qualification takes x1 and x2 as horizontal and x3 as vertical in "
        "space (the vertical spectrum drives x3)"]
    plane = write_deck(tmp_path, upright_cabinet(), "plane")
    code, err = invoke("qualify", plane, "--out", tmp_path / "q", "--rrs-x3", "v.csv")
    assert code == 2 and errors(err) == [
        "error: --rrs-x3: the deck is in the plane (2-D), whose vertical is x2: --rrs-x2 gives its RRS (x3 is the "
        "vertical of a deck in space)"]
    data = upright_cabinet()
    data["qualify"]["acceleration_limit_g"] = {"G": [2.0, 2.0, 1.5]}
    code, err = invoke("qualify", write_deck(tmp_path, data, "plane3"), "--out", tmp_path / "q")
    assert code == 2 and errors(err) == [
        "error: qualify.acceleration_limit_g.G: 3 values: one number for every direction or [x1, x2] (the deck is "
        "in the plane)"]
    assert not (tmp_path / "q").exists()


# ------------------------------------------------------------------ transmissibility


def with_point(plane: dict, prism: dict) -> tuple[dict, dict]:
    x, y = plane["body"]["vertices"][2]
    plane["output"] = {"points": [{"name": "p", "point": [x, y]}]}
    prism["output"] = {"points": [{"name": "p", "point": [x, y, 0.0]}]}
    return plane, prism


def test_a_prism_swept_in_its_plane_has_the_plane_transmissibility(tmp_path):
    plane, prism = with_point(*plane_and_prism("chang"))
    for direction in ("x1", "x2"):
        tables = {}
        for name, data in (("plane", plane), ("prism", prism)):
            out = tmp_path / f"{name}_{direction}"
            code, err = invoke("transmissibility", write_deck(tmp_path, data, name), "--direction", direction,
                               "--amplitude", "0.2", "--units", "g", "--frequencies", "3,12", "--workers", "1",
                               "--no-plots", "--out", out)
            assert code == 0, err
            tables[name] = read_csv(out / "transmissibility.csv")
        assert list(tables["prism"][0]) == ["frequency_hz", "amplitude_m_s2", "T_G_x1", "T_G_x2", "T_G_x3",
                                            "T_p_x1", "T_p_x2", "T_p_x3"]
        for flat, solid in zip(tables["plane"], tables["prism"]):
            for key, value in flat.items():
                assert float(solid[key]) == pytest.approx(float(value), rel=1e-9, abs=1e-12), (direction, key)
            assert float(solid["T_G_x3"]) < 1e-9 and float(solid["T_p_x3"]) < 1e-9


def test_a_sine_along_x3_gives_the_vertical_closed_form(tmp_path):
    """The prism's four vertical springs of k: T_x3 = 1 / |1 - r^2| (undamped), nothing in the plane."""
    _, prism = with_point(*plane_and_prism("chang"))
    prism["analysis"]["integrator"] = "adaptive"
    mass = rbhyst.load_deck(write_deck(tmp_path, prism, "prism")).body.mass
    f0 = math.sqrt(4 * 3.0e5 / mass) / (2 * math.pi)
    out = tmp_path / "x3"
    code, err = invoke("transmissibility", write_deck(tmp_path, prism, "prism"), "--direction", "x3", "--amplitude",
                       "0.1", "--units", "g", "--frequencies", f"{0.5 * f0!r},{2 * f0!r}", "--workers", "1",
                       "--out", out)
    assert code == 0, err
    rows = read_csv(out / "transmissibility.csv")
    for row in rows:
        r = float(row["frequency_hz"]) / f0
        assert float(row["T_G_x3"]) == pytest.approx(1 / abs(1 - r * r), rel=2e-3)
        assert float(row["T_p_x3"]) == pytest.approx(float(row["T_G_x3"]), rel=1e-9)
        assert max(float(row[k]) for k in ("T_G_x1", "T_G_x2", "T_p_x1", "T_p_x2")) < 1e-9
    assert json.loads((out / "transmissibility.json").read_text())["direction"] == "x3"
    assert (out / "transmissibility.png").exists() and "T_G_x3 from" in err


@pytest.mark.parametrize("space, direction, line", [
    (False, "x3", "--direction: 'x3': x1 or x2 (x3, the vertical, for a deck in space)"),
    (True, "x4", "--direction: 'x4': x1, x2 or x3"),
])
def test_a_direction_the_deck_does_not_have_is_one_line(tmp_path, space, direction, line):
    plane, prism = plane_and_prism("chang")
    deck = write_deck(tmp_path, prism if space else plane)
    code, err = invoke("transmissibility", deck, "--direction", direction, "--amplitude", "0.1", "--units", "g",
                       "--frequencies", "2", "--out", tmp_path / "t")
    assert code == 2 and errors(err) == [f"error: {line}"]
    assert not (tmp_path / "t").exists()


# ------------------------------------------------------------------ study


def test_the_study_of_a_prism_measures_six_coordinates_and_the_plane_three(tmp_path):
    plane, prism = plane_and_prism("chang")
    plane["analysis"]["duration"] = prism["analysis"]["duration"] = 1.0
    rows = {}
    for name, data in (("plane", plane), ("prism", prism)):
        out = tmp_path / name
        code, err = invoke("study", write_deck(tmp_path, data, name), "--integrators", "chang", "--dt",
                           "0.002,0.001", "--no-plots", "--out", out)
        assert code == 0, err
        rows[name] = read_csv(out / "study.csv")
        summary = json.loads((out / "study.json").read_text())
        assert summary["runs"][0]["err_max"] == pytest.approx(float(rows[name][0]["err_max"]), rel=1e-5)
    assert list(rows["plane"][0])[4:8] == ["err_u1", "err_u2", "err_theta3", "err_max"]
    assert list(rows["prism"][0])[4:11] == ["err_u1", "err_u2", "err_u3", "err_theta1", "err_theta2", "err_theta3",
                                            "err_max"]
    for flat, solid in zip(rows["plane"], rows["prism"]):
        for key in ("err_u1", "err_u2", "err_theta3", "err_max"):
            assert float(solid[key]) == pytest.approx(float(flat[key]), rel=1e-4), key
        assert max(float(solid[k]) for k in ("err_u3", "err_theta1", "err_theta2")) < 1e-9
        # the run's own estimate, in the deck's axes, is its error
        assert 0.5 < float(solid["est_over_true"]) < 2.0


def test_the_study_of_the_sample_in_space_writes_its_plots(tmp_path):
    data = rbhyst.load_deck(DECKS / "cabinet_3d.toml").model_dump(mode="python", exclude_unset=True)
    for axis in ("x1", "x2", "x3"):
        data["excitation"]["support"][axis]["file"] = str(DECKS / data["excitation"]["support"][axis]["file"])
    data["analysis"]["duration"] = 2.0
    data.pop("output")
    code, err = invoke("study", write_deck(tmp_path, data), "--integrators", "chang", "--dt", "0.002,0.001",
                       "--out", tmp_path / "s")
    assert code == 0, err
    assert {p.name for p in (tmp_path / "s").iterdir()} >= {"study.csv", "study.json", "error_vs_dt.png",
                                                            "error_vs_runtime.png"}


# ------------------------------------------------------------------ sweeps


def test_a_sweep_motion_carries_x3_for_a_deck_in_space(tmp_path):
    _, prism = plane_and_prism("chang")
    prism["analysis"]["duration"] = 1.0
    deck = write_deck(tmp_path, prism, "prism")
    sine = {"type": "sine", "amplitude": 0.2, "frequency_hz": 4.0, "units": "g"}
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('deck = "prism.toml"\n\n[[motions]]\nname = "vertical"\n'
                     'x3 = { type = "sine", amplitude = 0.2, frequency_hz = 4.0, units = "g" }\n\n'
                     '[[motions]]\nname = "both"\n'
                     'x1 = { type = "sine", amplitude = 0.2, frequency_hz = 4.0, units = "g" }\n'
                     'x3 = { type = "sine", amplitude = 0.2, frequency_hz = 4.0, units = "g" }\n\n'
                     '[scale]\nfactors = [1.0, 2.0]\n')
    code, err = invoke("sweep", sweep, "--workers", "1", "--no-plots", "--out", tmp_path / "out")
    assert code == 0, err
    cases = read_csv(tmp_path / "out" / "cases.csv")
    assert [(c["motion"], c["scale"]) for c in cases] == [("vertical", "1.0"), ("vertical", "2.0"), ("both", "1.0"),
                                                          ("both", "2.0")]
    alone = rbhyst.run(rbhyst.load_deck(deck).with_values({"excitation.support": {"x3": sine}}))
    assert float(cases[0]["peak_u3_m"]) == pytest.approx(alone.extremes.peak("u3_m"), rel=1e-12)
    assert float(cases[1]["peak_u3_m"]) == pytest.approx(2 * float(cases[0]["peak_u3_m"]), rel=1e-6)  # linear
    assert float(cases[0]["peak_u1_m"]) < 1e-12 < float(cases[2]["peak_u1_m"])


def test_a_sweep_motion_along_x3_is_refused_for_a_plane_deck(tmp_path):
    plane, _ = plane_and_prism("chang")
    write_deck(tmp_path, plane, "plane")
    (tmp_path / "rec").mkdir()
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('deck = "plane.toml"\n\n[[motions]]\nname = "m"\n'
                     'x1 = { type = "sine", amplitude = 0.2, frequency_hz = 4.0, units = "g" }\n'
                     'x3 = { type = "sine", amplitude = 0.2, frequency_hz = 4.0, units = "g" }\n\n'
                     '[[motion_folders]]\nfolder = "rec"\nx1 = "*_h.csv"\nx3 = "*_v.csv"\nunits = "g"\n')
    code, err = invoke("sweep", sweep, "--workers", "1", "--out", tmp_path / "out")
    assert code == 2 and errors(err) == [
        f"error: {key}: the deck plane.toml is in the plane (2-D): support motion along x1 and x2 only (x3 is for a "
        "deck in space)" for key in ("motions[1].x3", "motion_folders[1].x3")]
    assert not (tmp_path / "out").exists()
