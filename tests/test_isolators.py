"""[[isolators]] (docs/reference/deck.md, "Isolators"): a mount with an axial and shear behaviour as one entry with
local axes gives exactly the run of its elements written by hand, in space and in the plane; its
default shear lines; every mistake in it is one line naming its key (exit 2)."""

from __future__ import annotations

import copy
import json
import math
import tomllib

import numpy as np
import pytest

from rbhyst.model.deck import parse_deck
from rbhyst.model.isolators import default_shear, default_shear_deg
from conftest import DECKS, TABLE3_AXIAL, TABLE3_SHEAR, invoke, seed_deck, write_deck

SETS = {"axial": "wri_axial", "shear": "wri_shear"}


def cabinet(duration: float = 1.0) -> dict:
    """decks/cabinet_3d.toml without its isolators and elements (its records made absolute), short."""
    data = tomllib.loads((DECKS / "cabinet_3d.toml").read_text())
    for k in ("elements", "isolators", "qualify"):
        data.pop(k, None)
    for x in data["excitation"]["support"].values():
        x["file"] = str(DECKS / x["file"])
    data["analysis"]["duration"] = duration
    data.pop("output")
    data["output"] = {"points": tomllib.loads((DECKS / "cabinet_3d.toml").read_text())["output"]["points"]}
    return data


def hand_cabinet() -> dict:
    """The cabinet's four isolators written as twelve elements: under each corner, axial along -x3,
    shear along x1 and x2."""
    data = cabinet()
    data["elements"] = [{"vertex": v, "direction": d, "hysteresis": h}
                        for v in (1, 2, 3, 4)
                        for d, h in (([0.0, 0.0, -1.0], "wri_axial"), ([1.0, 0.0, 0.0], "wri_shear"),
                                     ([0.0, 1.0, 0.0], "wri_shear"))]
    return data


def isolator_cabinet() -> dict:
    data = cabinet()
    data["isolators"] = [{"vertex": v, "axial": [0.0, 0.0, -1.0], "hysteresis": dict(SETS)} for v in (1, 2, 3, 4)]
    return data


def run_files(tmp_path, name: str, data: dict) -> tuple[bytes, dict, str]:
    """`rbhyst run` of the deck: time_history.csv's bytes, summary.json, what it printed."""
    from typer.testing import CliRunner

    from rbhyst.cli import app

    out = tmp_path / f"out_{name}"
    res = CliRunner().invoke(app, ["run", str(write_deck(tmp_path, data, name)), "--no-plots", "--out", str(out)])
    assert res.exit_code == 0, res.stderr
    return (out / "time_history.csv").read_bytes(), json.loads((out / "summary.json").read_text()), res.stderr


def _same_numbers(a, b, path=""):
    """Two summaries agree in every number and string but the wall times (and the isolator's own keys)."""
    if isinstance(a, dict):
        keys = set(a) | set(b)
        for k in keys - {"wall_s", "isolator", "role"}:
            assert k in a and k in b, f"{path}.{k}"
            _same_numbers(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same_numbers(x, y, f"{path}[{i}]")
    elif not path.endswith(("wall_s", "_ms")) and "time" not in path.rsplit(".", 1)[-1]:
        assert a == b, path


def _strip_timing(summary: dict) -> dict:
    """A summary without what differs by construction: the deck as written, the timings, and when,
    by which command and from which files it ran."""
    s = copy.deepcopy(summary)
    for k in ("timing", "deck", "provenance"):
        s.pop(k, None)
    return s


# ------------------------------------------------------------------ the same run as by hand


@pytest.mark.parametrize("kinematics", ["small", "exact"])
def test_the_cabinet_on_isolators_is_the_cabinet_on_its_elements(tmp_path, kinematics):
    hand, iso = hand_cabinet(), isolator_cabinet()
    for data in (hand, iso):
        data["analysis"]["kinematics"] = kinematics
    hand_csv, hand, _ = run_files(tmp_path, "hand", hand)
    iso_csv, iso, printed = run_files(tmp_path, "iso", iso)
    assert iso_csv == hand_csv
    _same_numbers(_strip_timing(hand), _strip_timing(iso))
    # each element says which isolator and direction it is, in CSV order: axial, shear 1, shear 2
    assert [(e["isolator"], e["role"]) for e in iso["elements"]] == [
        (k, r) for k in (1, 2, 3, 4) for r in ("axial", "shear1", "shear2")]
    assert [e["direction"] for e in iso["elements"][:3]] == [[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    assert not any("isolator" in e for e in hand["elements"])
    assert "1 axial" in printed and "4 shear2" in printed and "isolator" in printed


def test_the_sample_deck_is_its_hand_written_twin():
    """decks/cabinet_3d.toml as a user writes it expands to the hand-written elements, in order."""
    deck = parse_deck(tomllib.loads((DECKS / "cabinet_3d.toml").read_text()))
    hand = parse_deck(hand_cabinet())
    assert deck.all_elements == hand.all_elements


def test_the_seed_on_isolators_is_the_seed_on_its_elements(tmp_path):
    """In the plane: two isolators of count 2, axial along x1 (the seed's), the default shear line at 90."""
    hand = seed_deck(duration=0.5)
    iso = copy.deepcopy(hand)
    del iso["elements"]
    iso["isolators"] = [{"vertex": v, "axial_deg": 0.0, "hysteresis": dict(SETS), "count": 2} for v in (1, 2)]
    hand_csv, hand_summary, _ = run_files(tmp_path, "hand", hand)
    iso_csv, iso_summary, _ = run_files(tmp_path, "iso", iso)
    assert iso_csv == hand_csv
    _same_numbers(_strip_timing(hand_summary), _strip_timing(iso_summary))
    assert [(e["isolator"], e["role"], e["angle_deg"]) for e in iso_summary["elements"]] == [
        (1, "axial", 0.0), (1, "shear", 90.0), (2, "axial", 0.0), (2, "shear", 90.0)]


def test_the_cabinet_with_a_transformer_on_isolators_is_the_same(tmp_path):
    """In the plane with body parts and the axial lines down (270 deg): the default shear line is
    0 deg, as written by hand (not 360: its sine is not zero in floating point)."""
    hand = tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())
    for x in hand["excitation"]["support"].values():
        x["file"] = str(DECKS / x["file"])
    hand["analysis"]["duration"] = 1.0
    hand.pop("output", None)
    iso = copy.deepcopy(hand)
    del iso["elements"]
    iso["isolators"] = [{"part": 1, "vertex": v, "axial_deg": 270.0, "hysteresis": dict(SETS), "count": 2}
                        for v in (1, 2)]
    assert parse_deck(iso).all_elements == parse_deck(hand).all_elements
    hand_csv, hand_summary, _ = run_files(tmp_path, "hand", hand)
    iso_csv, iso_summary, _ = run_files(tmp_path, "iso", iso)
    assert iso_csv == hand_csv
    _same_numbers(_strip_timing(hand_summary), _strip_timing(iso_summary))


def test_isolators_follow_the_elements_with_their_strokes_and_sets():
    data = hand_cabinet()
    data["elements"] = data["elements"][:3]  # corner 1 by hand
    data["hysteresis"]["soft"] = copy.deepcopy(TABLE3_SHEAR)
    data["isolators"] = [{"point": [0.4, 0.3, 0.0], "axial": [0.0, 0.0, -2.0],
                          "shear": [[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
                          "hysteresis": {"axial": "wri_axial", "shear1": "wri_shear", "shear2": "soft"},
                          "count": 3, "stroke": {"axial": [-0.02, 0.03], "shear2": 0.05}}]
    deck = parse_deck(data)
    entries = deck.element_entries
    assert [o.label for _, o in entries] == ["elements[1]", "elements[2]", "elements[3]", "isolators[1] axial",
                                             "isolators[1] shear1", "isolators[1] shear2"]
    axial, s1, s2 = (el for el, _ in entries[3:])
    assert (axial.direction, axial.hysteresis, axial.count, axial.stroke) == ([0.0, 0.0, -2.0], "wri_axial", 3,
                                                                              [-0.02, 0.03])
    assert (s1.direction, s1.hysteresis, s1.stroke) == ([1.0, 1.0, 0.0], "wri_shear", None)
    assert (s2.direction, s2.hysteresis, s2.stroke, s2.point) == ([-1.0, 1.0, 0.0], "soft", 0.05, [0.4, 0.3, 0.0])


def test_a_sweep_key_reaches_an_isolator():
    deck = parse_deck(isolator_cabinet()).with_values({"isolators[2].count": 2,
                                                       "isolators[3].hysteresis.shear": "wri_axial"})
    counts = [el.count for el in deck.all_elements]
    assert counts == [1, 1, 1, 2, 2, 2, 1, 1, 1, 1, 1, 1]
    assert [el.hysteresis for el in deck.all_elements[6:9]] == ["wri_axial"] * 3


# ------------------------------------------------------------------ default shear lines


@pytest.mark.parametrize("axial, shear", [
    ([0.0, 0.0, -1.0], ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])),
    ([0.0, 0.0, 3.0], ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])),
    ([-1.0, 0.0, 0.0], ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])),
    ([0.0, 2.0, 0.0], ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0])),
])
def test_default_shear_lines_along_an_axis_are_the_other_axes(axial, shear):
    assert default_shear(axial) == shear
    assert all(math.copysign(1.0, x) == 1.0 for s in default_shear(axial) for x in s if x == 0.0)  # no -0


@pytest.mark.parametrize("axial", [[0.2, -0.1, -1.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0], [-3.0, 0.5, 2.0]])
def test_default_shear_lines_are_orthonormal_and_near_the_axes(axial):
    a = np.asarray(axial) / np.linalg.norm(axial)
    s1, s2 = map(np.asarray, default_shear(axial))
    frame = np.array([a, s1, s2])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    j = int(np.argmax(np.abs(a)))
    p, q = (i for i in range(3) if i != j)
    assert s1[p] > 0 and s2[q] > 0  # towards the positive side of the deck axes they come from
    # shear 1 is the line perpendicular to the axial one nearest its deck axis
    best = np.eye(3)[p] - a[p] * a
    np.testing.assert_allclose(s1, best / np.linalg.norm(best), atol=1e-15)


@pytest.mark.parametrize("axial, shear", [(-90.0, 0.0), (90.0, 0.0), (270.0, 0.0), (0.0, 90.0), (180.0, 90.0),
                                          (45.0, 135.0), (30.0, 120.0), (-60.0, 30.0), (135.0, 45.0),
                                          (240.0, 330.0), (-45.0, 45.0)])
def test_default_shear_line_in_the_plane(axial, shear):
    assert default_shear_deg(axial) == shear
    a, s = math.radians(axial), math.radians(shear)
    assert abs(math.cos(a - s)) < 1e-15  # perpendicular
    # towards the positive side of the deck axis farther from the axial line
    assert (math.cos(s) > 0.5) if abs(math.sin(a)) > abs(math.cos(a)) + 1e-12 else (math.sin(s) > 0.5)


# ------------------------------------------------------------------ mistakes: one line naming the key


def space_deck(**iso) -> dict:
    data = isolator_cabinet()
    data["isolators"][0].update(iso)
    return data


def plane_deck(**iso) -> dict:
    data = seed_deck(duration=0.5)
    del data["elements"]
    data["isolators"] = [{"vertex": v, "axial_deg": 0.0, "hysteresis": dict(SETS), "count": 2} for v in (1, 2)]
    data["isolators"][0].update(iso)
    return data


@pytest.mark.parametrize("deck, line", [
    (space_deck(shear=[[1.0, 0.0, 0.1], [0.0, 1.0, 0.0]]),
     "isolators[1].shear[1]: [1, 0, 0.1] is 84.29 deg from the axial line [0, 0, -1]: a shear line is "
     "perpendicular to it (within 0.1 deg)"),
    (space_deck(shear=[[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]),
     "isolators[1].shear[2]: [1, 1, 0] is 45 deg from shear[1] [1, 0, 0]: the two shear lines are perpendicular "
     "to each other (within 0.1 deg)"),
    (space_deck(shear=[[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]),
     "isolators[1].shear[2]: [0, 0, 0] has no direction: give the shear line, any length but zero"),
    (space_deck(shear=[1.0, 0.0, 0.0]),
     "isolators[1].shear: 1 line given: an isolator in space has two shear lines, [[d1, d2, d3], [d1, d2, d3]] "
     "(or leave it out for the default ones)"),
    (space_deck(shear="x1"),
     "isolators[1].shear: 'x1' must be two shear lines, [[d1, d2, d3], [d1, d2, d3]]"),
    (plane_deck(shear=[0.0, 1.0]),
     "isolators[1].shear: the deck is in the plane (2-D): give the shear line as shear_deg from x1, or leave it "
     "out (axial_deg +- 90)"),
    (space_deck(shear=[[1.0, 0.0], [0.0, 1.0, 0.0]]),
     "isolators[1].shear[1]: [1, 0]: the deck is in space (3-D): three components [d1, d2, d3]"),
    (space_deck(axial=[0.0, 0.0, 0.0]),
     "isolators[1].axial: [0, 0, 0] has no direction: give the axial line, any length but zero"),
    (space_deck(axial=[0.0, -1.0]),
     "isolators[1].axial: [0, -1]: the deck is in space (3-D): three components [d1, d2, d3]"),
    ({**space_deck(), "isolators": [{"vertex": 1, "axial_deg": -90.0, "hysteresis": dict(SETS)}]},
     "isolators[1].axial_deg: the deck is in space (3-D): give the axial line as axial = [d1, d2, d3]"),
    ({**space_deck(), "isolators": [{"vertex": 1, "hysteresis": dict(SETS)}]},
     "isolators[1].axial: required key is missing"),
    (space_deck(hysteresis={"axial": "wri_axial", "shear": "nope"}),
     "isolators[1].hysteresis.shear: undefined set 'nope'; defined: wri_axial, wri_shear"),
    (space_deck(hysteresis={"axial": "wri_axial", "shear": "wri_shear", "shear2": "wri_shear"}),
     "isolators[1].hysteresis.shear2: not with `shear` (that of both shear lines): give `shear`, or `shear1` and "
     "`shear2`"),
    (space_deck(hysteresis={"axial": "wri_axial", "shear1": "wri_shear"}),
     "isolators[1].hysteresis.shear2: required key is missing (or one `shear` set for both shear lines)"),
    (space_deck(hysteresis={"shear": "wri_shear"}), "isolators[1].hysteresis.axial: required key is missing"),
    (space_deck(hysteresis="wri_axial"),
     "isolators[1].hysteresis: 'wri_axial': an isolator takes a set for each direction: "
     "{ axial = \"...\", shear = \"...\" } (or shear1 and shear2 in space)"),
    (space_deck(stroke={"axial": -0.01}),
     "isolators[1].stroke.axial: -0.01 must be a positive number (m) or [lower, upper] with lower < 0 < upper (m)"),
    (space_deck(stroke={"axial": 0.03, "axis": 0.03}), "isolators[1].stroke.axis: unknown key"),
    (space_deck(vertex=9), "isolators[1].vertex: 9 is out of range: the body has 8 vertices"),
    (space_deck(point=[0.0, 0.0, 0.0]),
     "isolators[1]: give exactly one of `vertex` (1-based index) or `point` ([x1, x2] in m)"),
    ({**space_deck(), "isolators": [{"point": [0.0, 0.0], "axial": [0.0, 0.0, -1.0], "hysteresis": dict(SETS)}]},
     "isolators[1].point: List should have at least 3 items: the deck is in space (3-D), as its body's first "
     "vertex (or box) says, and every point in it has 3 coordinates"),
    (space_deck(direction=[0.0, 0.0, -1.0]), "isolators[1].direction: unknown key"),
    (space_deck(count=0), "isolators[1].count: must be greater than or equal to 1"),
    (plane_deck(axial=[1.0, 0.0]),
     "isolators[1].axial: the deck is in the plane (2-D): give the axial line as axial_deg from x1 (counterclockwise)"),
    (plane_deck(shear_deg=80.0),
     "isolators[1].shear_deg: 80 is 80 deg from axial_deg = 0: the shear line is perpendicular to the axial line "
     "(within 0.1 deg)"),
    (plane_deck(shear=[[0.0, 1.0], [0.0, 1.0]]),
     "isolators[1].shear: the deck is in the plane (2-D): give the shear line as shear_deg from x1, or leave it "
     "out (axial_deg +- 90)"),
    (plane_deck(hysteresis={"axial": "wri_axial", "shear1": "wri_shear"}),
     "isolators[1].hysteresis.shear1: the deck is in the plane (2-D): an isolator has one shear line there (`shear`)"),
    (plane_deck(stroke={"shear2": 0.05}),
     "isolators[1].stroke.shear2: the deck is in the plane (2-D): an isolator has one shear line there (`shear`)"),
    ({**plane_deck(), "isolators": [{"vertex": 1, "hysteresis": dict(SETS)}]},
     "isolators[1].axial_deg: required key is missing"),
    ({**plane_deck(), "isolators": [{"vertex": 1, "axial_deg": 0.0, "hysteresis": {"axial": "wri_axial"}}]},
     "isolators[1].hysteresis.shear: required key is missing"),
])
def test_a_mistake_in_an_isolator_is_one_line_naming_its_key(tmp_path, deck, line):
    code, err = invoke("run", write_deck(tmp_path, deck), "--no-plots")
    assert code == 2
    assert err.splitlines() == [f"error: {line}"]
    assert "Traceback" not in err


def test_a_deck_without_elements_or_isolators_says_which_it_needs(tmp_path):
    data = seed_deck()
    del data["elements"]
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots")
    assert code == 2
    assert err.splitlines() == ["error: elements: required for an analysis ([[elements]] or [[isolators]])"]


def test_a_stroke_warning_names_the_isolator_and_direction(tmp_path):
    import rbhyst

    data = plane_deck(stroke={"shear": 1e-4})
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    [warning] = [w for w in res.warnings if "stroke" in w]
    assert warning.startswith("element e3-e4 (isolators[1] shear, 'wri_shear') goes beyond its stroke")
