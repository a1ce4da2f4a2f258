"""Bodies of several parts, or of properties given directly: mass properties, references, decks."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
import scipy.linalg
from typer.testing import CliRunner

from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.errors import InputError
from rbhyst.model.geometry import composite, contains, polygon
from rbhyst.model.system import assemble
from rbhyst.solve.plan import Settings, simulate
from conftest import SEED_MASS, SEED_VERTICES, seed_deck, square_linear_deck, write_deck

# the documentation's cabinet (docs/reference/deck.md, Body): a uniform shell 0.8 m x 2.0 m and a dense
# unit 0.6 m x 0.4 m inside it
SHELL = [[0.0, 0.0], [0.8, 0.0], [0.8, 2.0], [0.0, 2.0]]
UNIT = [[0.1, 0.2], [0.7, 0.2], [0.7, 0.6], [0.1, 0.6]]
M_SHELL, M_UNIT = 300.0, 250.0


def cabinet_deck() -> dict:
    """The cabinet on three linear springs at corners of the shell."""
    deck = square_linear_deck()
    deck["body"] = {"parts": [{"vertices": copy.deepcopy(SHELL), "mass": M_SHELL},
                              {"vertices": copy.deepcopy(UNIT), "mass": M_UNIT}]}
    deck["elements"] = [
        {"part": 1, "vertex": 1, "angle_deg": 0.0, "hysteresis": "lin"},
        {"part": 1, "vertex": 1, "angle_deg": 90.0, "hysteresis": "lin"},
        {"part": 1, "vertex": 2, "angle_deg": 90.0, "hysteresis": "lin"},
    ]
    return deck


def direct_deck(**body) -> dict:
    """The cabinet's properties as a CAD model would give them, with the shell as outline."""
    deck = cabinet_deck()
    deck["body"] = {"mass": 550.0, "mass_centre": [0.4, 0.72], "inertia": 176.0,
                    "vertices": copy.deepcopy(SHELL), **body}
    deck["elements"] = [dict(e) for e in deck["elements"]]
    for e in deck["elements"]:
        del e["part"]
    return deck


# ---------------------------------------------------------------- mass properties


def test_two_rectangles_one_inside_the_other_by_the_parallel_axis_theorem(tmp_path):
    # each rectangle about its own centroid: J_i = m_i (b_i^2 + h_i^2) / 12
    b1, h1, c1 = 0.8, 2.0, np.array([0.4, 1.0])
    b2, h2, c2 = 0.6, 0.4, np.array([0.4, 0.4])
    j1 = M_SHELL * (b1**2 + h1**2) / 12  # 116.0
    j2 = M_UNIT * (b2**2 + h2**2) / 12  # 10.8333...
    # the whole: m = m1 + m2, G = (m1 c1 + m2 c2) / m, J = sum J_i + m_i |c_i - G|^2
    m = M_SHELL + M_UNIT
    g = (M_SHELL * c1 + M_UNIT * c2) / m  # (0.4, 8/11)
    j = j1 + M_SHELL * np.sum((c1 - g) ** 2) + j2 + M_UNIT * np.sum((c2 - g) ** 2)
    assert g[1] == pytest.approx(8 / 11, rel=1e-15)
    assert j == pytest.approx(116.0 + 32.5 / 3 + 5940 / 121, rel=1e-14)  # on paper: 175.924...

    mass, centre, inertia = composite([(SHELL, M_SHELL), (UNIT, M_UNIT)])
    assert mass == m
    np.testing.assert_allclose(centre, g, rtol=1e-14)
    assert inertia == pytest.approx(j, rel=1e-13)

    system = assemble(parse_deck(cabinet_deck()), tmp_path)
    np.testing.assert_allclose(system.mass, [m, m, j], rtol=1e-13)
    np.testing.assert_allclose(system.body.mass_centre, g, rtol=1e-14)


def test_one_part_is_the_single_polygon_bit_for_bit(tmp_path):
    single = seed_deck()
    parts = seed_deck()
    parts["body"] = {"parts": [{"vertices": SEED_VERTICES, "mass": SEED_MASS}]}
    a, b = assemble(parse_deck(single), tmp_path), assemble(parse_deck(parts), tmp_path)
    np.testing.assert_array_equal(a.mass, b.mass)
    assert a.mass[2] == polygon(SEED_VERTICES).polar_inertia(SEED_MASS)
    np.testing.assert_array_equal(a.body.mass_centre, b.body.mass_centre)
    np.testing.assert_array_equal(a.body.outlines[0], b.body.outlines[0])
    np.testing.assert_array_equal(a.bvec, b.bvec)  # `vertex` alone is part 1's when there is one part
    assert [e.x for e in a.elements] == [e.x for e in b.elements]
    # the same shift, said of the key the deck used
    assert [n.split(": ", 1)[1] for n in a.notes] == [n.split(": ", 1)[1] for n in b.notes]


@pytest.mark.parametrize("halves", [
    # a vertical cut at x1 = 0.45: masses 0.45/1.2 and 0.75/1.2 of the whole
    [([[0, 0], [0.45, 0], [0.45, 0.5], [0, 0.5]], 0.45 / 1.2), ([[0.45, 0], [1.2, 0], [1.2, 0.5], [0.45, 0.5]], 0.75 / 1.2)],
    # the diagonal: two triangles of equal area, one clockwise
    [([[0, 0], [1.2, 0], [1.2, 0.5]], 0.5), ([[0, 0], [0, 0.5], [1.2, 0.5]], 0.5)],
])
def test_a_rectangle_split_in_two_is_the_whole(halves):
    m = 90.0
    whole = polygon([[0, 0], [1.2, 0], [1.2, 0.5], [0, 0.5]])
    mass, centre, inertia = composite([(v, m * share) for v, share in halves])
    assert mass == pytest.approx(m, rel=1e-15)
    np.testing.assert_allclose(centre, whole.centroid, rtol=1e-14)
    assert inertia == pytest.approx(whole.polar_inertia(m), rel=1e-13)  # m (b^2 + h^2) / 12
    assert inertia == pytest.approx(m * (1.2**2 + 0.5**2) / 12, rel=1e-13)


def test_direct_properties_pass_through(tmp_path):
    system = assemble(parse_deck(direct_deck()), tmp_path)
    np.testing.assert_array_equal(system.mass, [550.0, 550.0, 176.0])
    np.testing.assert_array_equal(system.body.mass_centre, [0.4, 0.72])
    np.testing.assert_array_equal(system.body.outline, np.array(SHELL) - [0.4, 0.72])
    assert system.elements[2].x == (0.8 - 0.4, 0.0 - 0.72)  # vertex 2 of the outline, about G
    assert not [n for n in system.notes if "outside" in n]


def test_implausible_direct_properties_get_a_note(tmp_path):
    outside = assemble(parse_deck(direct_deck(mass_centre=[1.0, 0.5])), tmp_path)
    assert any(n.startswith("body.mass_centre (1, 0.5) m lies outside the outline") for n in outside.notes)
    # r_max about G = (0.4, 0.72) is the top corners' hypot(0.4, 1.28): J above m r_max^2 is mass beyond them
    r2 = 0.4**2 + 1.28**2
    fine = assemble(parse_deck(direct_deck(inertia=0.999 * 550 * r2)), tmp_path)
    beyond = assemble(parse_deck(direct_deck(inertia=1.001 * 550 * r2)), tmp_path)
    assert not [n for n in fine.notes if n.startswith("body.inertia")]
    assert [n for n in beyond.notes if n.startswith("body.inertia")]


@pytest.mark.parametrize("point, inside", [
    ((0.0, 0.0), True), ((-0.1286, 0.0), True), ((-0.1286, 0.5), True),  # where the arm joins; an edge
    ((-0.5, 0.5), False), ((-0.5, -0.7), False), ((-0.5, 0.2), True),  # above, below and in the seed's arm
    ((0.4714, -0.9429), True), ((0.48, 0.0), False),  # a vertex; just outside
])
def test_point_in_polygon(point, inside):
    assert contains(SEED_VERTICES, point) is inside


# ---------------------------------------------------------------- element references


def test_part_and_vertex_resolve_to_that_point_about_g(tmp_path):
    deck = cabinet_deck()
    deck["elements"].append({"part": 2, "vertex": 3, "angle_deg": 45.0, "hysteresis": "lin"})
    deck["elements"].append({"point": [0.7, 0.6], "angle_deg": 45.0, "hysteresis": "lin"})
    system = assemble(parse_deck(deck), tmp_path)
    g = composite([(SHELL, M_SHELL), (UNIT, M_UNIT)])[1]
    assert system.elements[0].x == (0.0 - g[0], 0.0 - g[1])  # part 1, vertex 1
    assert system.elements[2].x == (0.8 - g[0], 0.0 - g[1])  # part 1, vertex 2
    assert system.elements[3].x == (0.7 - g[0], 0.6 - g[1])  # part 2, vertex 3 ...
    assert system.elements[4].x == system.elements[3].x  # ... is the point it names
    assert system.elements[3].x == pytest.approx((0.3, 0.6 - 8 / 11), rel=1e-14)
    # same point, same angle, same set: one kernel row
    assert system.elements[3].row == system.elements[4].row


# ---------------------------------------------------------------- deck mistakes

runner = CliRunner()


def _run(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res.exit_code, res.stderr


def _put(path: str, value):
    def change(deck):
        *keys, last = path.split(".")
        d = deck
        for k in keys:
            d = d[int(k)] if k.isdigit() else d[k]
        if last.isdigit():
            d[int(last)] = value
        else:
            d[last] = value
    return change


def _drop(path: str):
    def change(deck):
        *keys, last = path.split(".")
        d = deck
        for k in keys:
            d = d[int(k)] if k.isdigit() else d[k]
        del d[int(last) if last.isdigit() else last]
    return change


PARTS_MISTAKES = [
    ("parts and mass", _put("body.mass", 550.0), "body.mass: not with body.parts"),
    ("parts and vertices", _put("body.vertices", SHELL), "body.vertices: not with body.parts"),
    ("parts and inertia", _put("body.inertia", 176.0), "body.inertia: not with body.parts"),
    ("no parts", _put("body.parts", []), "body.parts: List should have at least 1 item"),
    ("part without mass", _drop("body.parts.1.mass"), "body.parts[2].mass: required key is missing"),
    ("part with density", _put("body.parts.1.density", 7800.0), "body.parts[2].density: unknown key"),
    ("part of zero mass", _put("body.parts.0.mass", 0.0), "body.parts[1].mass: must be greater than 0"),
    ("part of two vertices", _put("body.parts.1.vertices", [[0, 0], [1, 0]]),
     "body.parts[2].vertices: List should have at least 3 items"),
    ("part vertex of three numbers", _put("body.parts.1.vertices.0", [0.1, 0.2, 0.0]),
     "body.parts[2].vertices[1]: List should have at most 2 items"),
    ("part of zero area", _put("body.parts.1.vertices", [[0, 0], [1, 0], [2, 0]]),
     "body.parts[2].vertices: the polygon has zero area"),
    ("part with crossing edges", _put("body.parts.1.vertices", [[0, 0], [1, 1], [1, 0], [0, 1]]),
     "body.parts[2].vertices: edges P1-P2 and P3-P4 intersect"),
    ("vertex of which part", _drop("elements.0.part"), "elements[1].vertex: the body has 2 parts: say whose"),
    ("part out of range", _put("elements.0.part", 3), "elements[1].part: 3 is out of range: the body has 2 parts"),
    ("vertex out of the part", lambda d: d["elements"][0].update(part=2, vertex=5),
     "elements[1].vertex: 5 is out of range: body.parts[2] has 4 vertices"),
    ("part with a point", lambda d: d["elements"][0].update(point=[0.0, 0.0]) or d["elements"][0].pop("vertex"),
     "elements[1].part: goes with `vertex`"),
    ("part zero", _put("elements.0.part", 0), "elements[1].part: must be greater than or equal to 1"),
]
DIRECT_MISTAKES = [
    ("centre without inertia", _drop("body.inertia"), "body.inertia: required with body.mass_centre"),
    ("inertia without centre", _drop("body.mass_centre"), "body.mass_centre: required with body.inertia"),
    ("zero inertia", _put("body.inertia", 0.0), "body.inertia: must be greater than 0"),
    ("negative inertia", _put("body.inertia", -176.0), "body.inertia: must be greater than 0"),
    ("no outline", _drop("body.vertices"), "body.vertices: required key is missing"),
    ("no mass", _drop("body.mass"), "body.mass: required key is missing"),
    ("centre of three numbers", _put("body.mass_centre", [0.4, 0.72, 0.0]),
     "body.mass_centre: List should have at most 2 items"),
    ("outline crossing", _put("body.vertices", [[0, 0], [1, 1], [1, 0], [0, 1]]), "body.vertices: edges P1-P2"),
    ("part on an outline", _put("elements.0.part", 1), "elements[1].part: the body has no parts"),
]


def _check_one_line_exit_2_nothing_written(tmp_path, deck, expected, n_lines=1):
    out = tmp_path / "out"
    code, err = _run("run", write_deck(tmp_path, deck), "--out", out)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == n_lines and all(line.startswith("error: ") for line in lines), err
    assert any(line.startswith(f"error: {expected}") for line in lines), err
    assert not out.exists() and not list(tmp_path.glob(".out*"))


@pytest.mark.parametrize("name, change, expected", PARTS_MISTAKES, ids=[c[0] for c in PARTS_MISTAKES])
def test_parts_mistakes_get_one_line_naming_the_key(tmp_path, name, change, expected):
    deck = cabinet_deck()
    change(deck)
    _check_one_line_exit_2_nothing_written(tmp_path, deck, expected)


@pytest.mark.parametrize("name, change, expected", DIRECT_MISTAKES, ids=[c[0] for c in DIRECT_MISTAKES])
def test_direct_property_mistakes_get_one_line_naming_the_key(tmp_path, name, change, expected):
    deck = direct_deck()
    change(deck)
    _check_one_line_exit_2_nothing_written(tmp_path, deck, expected)


def test_parts_with_properties_too_get_a_line_per_key(tmp_path):
    deck = cabinet_deck()
    deck["body"].update(direct_deck()["body"])
    for key in ("vertices", "mass", "mass_centre", "inertia"):
        _check_one_line_exit_2_nothing_written(tmp_path, deck, f"body.{key}: not with body.parts", n_lines=4)


def test_a_part_mistake_is_found_at_parse_time():
    deck = cabinet_deck()
    del deck["elements"][0]["part"]
    with pytest.raises(InputError) as exc:
        parse_deck(deck)
    assert exc.value.problems == ["elements[1].vertex: the body has 2 parts: say whose vertex with `part` (1 to 2)"]


# ---------------------------------------------------------------- runs


def test_two_part_body_vibrates_at_the_frequencies_of_its_m_and_k(tmp_path):
    """Free vibration after a force pulse: each modal coordinate of (K, M), with M from the parts
    by hand and K from the springs, crosses zero at its own natural frequency."""
    k = 2.0e5
    shell = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]
    unit = [[0.1, -0.4], [0.4, -0.4], [0.4, -0.1], [0.1, -0.1]]
    deck = square_linear_deck(k=k)
    deck["body"] = {"parts": [{"vertices": shell, "mass": M_SHELL}, {"vertices": unit, "mass": M_UNIT}]}
    deck["excitation"] = {"force": {
        "point": [0.3, 0.2],
        "p1": {"type": "sine", "amplitude": 1000.0, "frequency_hz": 5.0, "units": "N", "cycles": 1.0},
        "p2": {"type": "sine", "amplitude": 800.0, "frequency_hz": 7.0, "units": "N", "cycles": 1.0},
    }}
    system = assemble(parse_deck(deck), tmp_path)

    # M by hand: shell J = m (1 + 1) / 12 about (0, 0); unit J = m (0.09 + 0.09) / 12 about (0.25, -0.25)
    m = M_SHELL + M_UNIT
    g = (M_SHELL * np.array([0.0, 0.0]) + M_UNIT * np.array([0.25, -0.25])) / m
    j = (M_SHELL * 2 / 12 + M_SHELL * g @ g
         + M_UNIT * 0.18 / 12 + M_UNIT * (np.array([0.25, -0.25]) - g) @ (np.array([0.25, -0.25]) - g))
    mass = np.diag([m, m, j])
    # K = sum k b b^T, b = (cos a, sin a, x1 sin a - x2 cos a) with x about G
    springs = [((0.0, 0.5), 0.0), ((0.0, -0.5), 0.0), ((0.5, 0.0), 90.0), ((-0.5, 0.0), 90.0)]
    stiffness = np.zeros((3, 3))
    for (x1, x2), a in springs:
        x1, x2, a = x1 - g[0], x2 - g[1], math.radians(a)
        b = np.array([math.cos(a), math.sin(a), x1 * math.sin(a) - x2 * math.cos(a)])
        stiffness += k * np.outer(b, b)
    w2, modes = scipy.linalg.eigh(stiffness, mass)
    np.testing.assert_allclose(system.mass, np.diag(mass), rtol=1e-13)

    res = simulate(system, Settings(dt=1e-4, duration=3.0))
    free = res.time >= 0.25  # both pulses are over at 0.2 s
    t = res.time[free]
    for i in range(3):
        eta = res.d[free] @ (mass @ modes[:, i])  # modal coordinate: phi_i^T M q
        assert np.max(np.abs(eta)) > 1e-3 * np.max(np.abs(res.d[free] @ mass @ modes))
        s = np.signbit(eta)
        idx = np.nonzero(s[1:] != s[:-1])[0]
        crossings = t[idx] - eta[idx] * (t[idx + 1] - t[idx]) / (eta[idx + 1] - eta[idx])
        period = 2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
        # Chang's method lengthens a period by about (w dt)^2 / 12: 2.5e-6 for the highest mode here
        assert 2.0 * math.pi / period == pytest.approx(math.sqrt(w2[i]), rel=1e-5)
        # the coupling of translation and rotation through G's offset is real: no mode is pure
        assert np.count_nonzero(np.abs(modes[:, i]) > 1e-6) >= 2


def test_summary_gives_the_mass_centre_and_the_parts(tmp_path):
    deck = cabinet_deck()
    out = tmp_path / "out"
    code, err = _run("run", write_deck(tmp_path, deck), "--out", out, "--no-plots")
    assert code == 0, err
    body = json.loads((out / "summary.json").read_text())["body"]
    mass, centre, inertia = composite([(SHELL, M_SHELL), (UNIT, M_UNIT)])
    assert body["form"] == "parts" and "centroid_m" not in body and "vertices_m" not in body
    assert body["mass_kg"] == mass and body["inertia_kgm2"] == inertia
    assert body["mass_centre_m"] == centre.tolist()
    assert [p["mass_kg"] for p in body["parts"]] == [M_SHELL, M_UNIT]
    assert body["parts"][1]["centroid_m"] == pytest.approx([0.4, 0.4], rel=1e-15)
    assert body["parts"][1]["inertia_kgm2"] == pytest.approx(M_UNIT * (0.36 + 0.16) / 12, rel=1e-14)
    assert body["parts"][1]["vertices_m"] == (np.array(UNIT) - centre).tolist()


def test_summary_and_model_plot_of_given_properties(tmp_path):
    out = tmp_path / "out"
    code, err = _run("run", write_deck(tmp_path, direct_deck()), "--out", out)
    assert code == 0, err
    body = json.loads((out / "summary.json").read_text())["body"]
    assert body == {"form": "direct", "area_m2": 1.6, "mass_kg": 550.0, "inertia_kgm2": 176.0,
                    "mass_centre_m": [0.4, 0.72], "vertices_m": (np.array(SHELL) - [0.4, 0.72]).tolist()}
    assert (out / "model.png").stat().st_size > 10_000


def test_single_polygon_summary_keeps_its_centroid(tmp_path):
    out = tmp_path / "out"
    code, err = _run("run", write_deck(tmp_path, square_linear_deck()), "--out", out, "--no-plots")
    assert code == 0, err
    body = json.loads((out / "summary.json").read_text())["body"]
    assert body["form"] == "polygon"
    assert body["centroid_m"] == body["mass_centre_m"] == [0.0, 0.0]
    assert body["area_m2"] == 1.0 and body["inertia_kgm2"] == 500.0 / 6.0
    assert body["vertices_m"] == [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]
