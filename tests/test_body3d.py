"""A rigid body in space (docs/explanation/space.md): mass properties of polyhedra against closed
forms, a prism that reproduces the plane body's run, the principal-axes transform against the
same scene built in principal axes, the energy balance, second order against the modal closed
form, the error estimate against the true error, and deck mistakes."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import scipy.linalg

import rbhyst
from rbhyst.model.deck import parse_deck
from rbhyst.model.solid import box_vertices, parallel_axis3, polyhedron
from rbhyst.model.system import assemble
from conftest import DECKS, TABLE3_AXIAL, TABLE3_SHEAR, invoke, linear_set, seed_deck, write_deck
from test_accuracy import estimated, true_error

# ------------------------------------------------------------------ mass properties


def test_a_box_has_the_closed_form_inertia():
    a, b, c, m = 0.8, 0.6, 2.0, 550.0
    shape = polyhedron(box_vertices([a, b, c], [0.4, 0.3, 1.0]))
    assert abs(shape.volume - a * b * c) < 1e-12 * a * b * c
    np.testing.assert_allclose(shape.centroid, [0.4, 0.3, 1.0], rtol=0, atol=1e-12)
    exact = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(shape.inertia(m), exact, rtol=0, atol=1e-12 * np.abs(exact).max())
    assert len(shape.edges) == 12  # the faces' diagonals are not edges


def test_a_tetrahedron_has_the_closed_form_inertia():
    """The corner tetrahedron (0,0,0), (a,0,0), (0,b,0), (0,0,c): V = abc/6, centroid at a quarter
    of each edge; about the origin I11 = m (b^2 + c^2) / 10, products int x1 x2 dm = m a b / 20;
    moved to the centroid by the parallel-axis theorem."""
    a, b, c, m = 0.7, 1.1, 1.9, 12.0
    shape = polyhedron([[0, 0, 0], [a, 0, 0], [0, b, 0], [0, 0, c]])
    assert abs(shape.volume - a * b * c / 6.0) < 1e-12 * a * b * c
    g = np.array([a, b, c]) / 4.0
    np.testing.assert_allclose(shape.centroid, g, rtol=0, atol=1e-12)
    second = m / 20.0 * np.array([[2 * a * a, a * b, a * c], [a * b, 2 * b * b, b * c], [a * c, b * c, 2 * c * c]])
    about_origin = np.trace(second) * np.eye(3) - second
    exact = about_origin - m * (float(g @ g) * np.eye(3) - np.outer(g, g))
    np.testing.assert_allclose(shape.inertia(m), exact, rtol=0, atol=1e-12 * np.abs(exact).max())


def test_parts_combine_by_the_parallel_axis_theorem():
    """Two boxes side by side are one box of twice the length."""
    left = polyhedron(box_vertices([1.0, 0.5, 0.4], [0.5, 0.0, 0.0]))
    right = polyhedron(box_vertices([1.0, 0.5, 0.4], [1.5, 0.0, 0.0]))
    whole = polyhedron(box_vertices([2.0, 0.5, 0.4], [1.0, 0.0, 0.0]))
    m, g, j = parallel_axis3([(5.0, left.centroid, left.inertia(5.0)), (5.0, right.centroid, right.inertia(5.0))])
    assert m == 10.0
    np.testing.assert_allclose(g, whole.centroid, atol=1e-12)
    np.testing.assert_allclose(j, whole.inertia(10.0), rtol=0, atol=1e-12 * 10.0)


# ------------------------------------------------------------------ a prism against the plane body


def plane_and_prism(integrator: str, extra: dict | None = None) -> tuple[dict, dict]:
    """The seed scene, and the same body as a prism 0.4 m thick symmetric about G's plane (mass
    and J33 the plane body's), its elements in G's plane along their in-plane directions, and
    four vertical linear springs at (+-0.3, +-0.4) m from G that hold u3, theta1, theta2 without
    touching the plane motion."""
    # (the seed's small rotations, in which the prism's plane motion is the plane body's exactly)
    plane = seed_deck(duration=2.0, integrator=integrator, estimate_error=False, **{"kinematics": "small", **(extra or {})})
    system = assemble(parse_deck(plane), DECKS)
    g, j33, m = system.body.mass_centre, system.body.inertia, system.body.mass
    h = 0.4
    vertices = [[x, y, z] for z in (-h / 2, h / 2) for x, y in plane["body"]["vertices"]]
    prism = copy.deepcopy(plane)
    prism["body"] = {"mass": m, "mass_centre": [g[0], g[1], 0.0],
                     "inertia": [[0.6 * j33, 0.0, 0.0], [0.0, 0.8 * j33, 0.0], [0.0, 0.0, j33]],
                     "vertices": vertices}
    prism["hysteresis"]["vertical"] = linear_set(3.0e5)
    elements = []
    for el in plane["elements"]:
        p = plane["body"]["vertices"][el["vertex"] - 1]
        a = math.radians(el["angle_deg"])
        elements.append({"point": [p[0], p[1], 0.0], "direction": [math.cos(a), math.sin(a), 0.0],
                         "hysteresis": el["hysteresis"], "count": el["count"]})
    for dx, dy in ((0.3, 0.4), (-0.3, 0.4), (-0.3, -0.4), (0.3, -0.4)):
        elements.append({"point": [g[0] + dx, g[1] + dy, 0.0], "direction": [0.0, 0.0, 1.0],
                         "hysteresis": "vertical"})
    prism["elements"] = elements
    return plane, prism


@pytest.mark.parametrize("integrator", ["chang", "newmark", "adaptive"])
def test_a_prism_in_the_plane_of_g_reproduces_the_plane_run(tmp_path, integrator):
    # (the adaptive runs choose their steps from the error of every coordinate: they agree within
    # their tolerance, here far below the test's)
    plane, prism = plane_and_prism(integrator, {"rtol": 1e-12} if integrator == "adaptive" else None)
    flat = rbhyst.run(write_deck(tmp_path, plane, "plane"))
    solid = rbhyst.run(write_deck(tmp_path, prism, "prism"))
    assert solid.columns[1:7] == ("u1_m", "u2_m", "u3_m", "theta1_rad", "theta2_rad", "theta3_rad")
    for name in ("u1_m", "u2_m", "theta3_rad", "at1_m_s2", "at2_m_s2", "e1_f_N", "e3_f_N"):
        ref = flat.column(name)
        err = np.max(np.abs(solid.column(name) - ref)) / np.max(np.abs(ref))
        assert err < 1e-9, (integrator, name, err)
    assert np.max(np.abs(solid.column("R6_Nm") - flat.column("R3_Nm"))) < 1e-9 * np.max(np.abs(flat.column("R3_Nm")))
    scale = np.max(np.abs(flat.column("u1_m")))
    for name in ("u3_m", "theta1_rad", "theta2_rad"):
        assert np.max(np.abs(solid.column(name))) <= 1e-12 * scale, name


# ------------------------------------------------------------------ principal axes


def rotation_matrix(axis, angle: float) -> np.ndarray:
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def box_scene(turn: np.ndarray) -> dict:
    """A box 0.8 x 0.5 x 1.4 m on the seed's isolators at its bottom corners and on two inclined
    ones, a support motion along (1, 0.5, 0.3) and a point at a top corner, all turned by ``turn``
    about the box's centre (the origin): its inertia tensor is diagonal for turn = I only."""
    corners = box_vertices([0.8, 0.5, 1.4])
    elements = []
    for k in range(4):
        for d, name in (((0, 0, -1), "wri_axial"), ((1, 0, 0), "wri_shear"), ((0, 1, 0), "wri_shear")):
            elements.append({"point": list(turn @ corners[k]), "direction": list(turn @ np.array(d, float)),
                             "hysteresis": name})
    elements.append({"point": list(turn @ corners[1]), "direction": list(turn @ np.array([1.0, 1.0, 0.5])),
                     "hysteresis": "wri_shear"})
    along = turn @ np.array([1.0, 0.5, 0.3])
    support = {f"x{k + 1}": {"type": "sine", "amplitude": 0.3 * float(along[k]), "frequency_hz": 2.5, "units": "g",
                             "cycles": 3} for k in range(3)}
    return {
        "body": {"vertices": [list(turn @ v) for v in corners], "mass": 400.0},
        "hysteresis": {"wri_axial": copy.deepcopy(TABLE3_AXIAL), "wri_shear": copy.deepcopy(TABLE3_SHEAR)},
        "elements": elements,
        "excitation": {"support": support},
        "analysis": {"dt": 0.001, "duration": 2.0, "estimate_error": False},
        "output": {"points": [{"name": "top", "point": list(turn @ corners[6])}]},
    }


def test_a_turned_box_runs_in_principal_axes_and_answers_in_the_decks(tmp_path):
    turn = rotation_matrix([1.0, 2.0, 3.0], 0.4)
    straight = rbhyst.run(write_deck(tmp_path, box_scene(np.eye(3)), "straight"))
    turned = rbhyst.run(write_deck(tmp_path, box_scene(turn), "turned"))
    assert straight.system.frame is None and turned.system.frame is not None
    for family in (("u", "m"), ("theta", "rad"), ("at", "m_s2"), ("alphat", "rad_s2"), ("top_u", "m"),
                   ("top_at", "m_s2")):
        a = np.column_stack([straight.column(f"{family[0]}{k}_{family[1]}") for k in (1, 2, 3)])
        b = np.column_stack([turned.column(f"{family[0]}{k}_{family[1]}") for k in (1, 2, 3)])
        err = np.max(np.abs(b - a @ turn.T)) / np.max(np.abs(a))
        assert err < 1e-9, (family, err)
    for k in range(1, 14):
        f = straight.column(f"e{k}_f_N")
        assert np.max(np.abs(turned.column(f"e{k}_f_N") - f)) < 1e-9 * np.max(np.abs(f))
    forces = [np.column_stack([r.column(f"R{k}_{'N' if k <= 3 else 'Nm'}") for k in range(i, i + 3)])
              for r in (straight, turned) for i in (1, 4)]
    for a, b in ((forces[0], forces[2]), (forces[1], forces[3])):
        assert np.max(np.abs(b - a @ turn.T)) < 1e-9 * np.max(np.abs(a))
    # the modes are the same, their shapes turned with the body
    m1, m2 = straight.summary()["modes"], turned.summary()["modes"]
    np.testing.assert_allclose(m2["frequencies_hz"], m1["frequencies_hz"], rtol=1e-10)


# ------------------------------------------------------------------ energy and order


def linear_scene(dt: float = 0.001, integrator: str = "chang") -> dict:
    """A box turned about a skew axis (a full inertia tensor) on seven linear springs, loaded by a
    harmonic force at a point and a moment."""
    turn = rotation_matrix([0.3, -1.0, 0.6], 0.7)
    corners = box_vertices([0.9, 0.6, 1.2])
    rng = np.random.default_rng(7)
    springs = []
    for k in range(7):
        p = corners[k]
        d = rng.normal(size=3)
        springs.append({"point": list(turn @ p), "direction": list(d / np.linalg.norm(d)),
                        "hysteresis": f"k{k}"})
    return {
        "body": {"vertices": [list(turn @ v) for v in corners], "mass": 300.0},
        "hysteresis": {f"k{k}": linear_set(1.0e5 * (1.0 + 0.3 * k)) for k in range(7)},
        "elements": springs,
        "excitation": {"force": {"point": [0.2, -0.1, 0.5],
                                 "p1": {"type": "sine", "amplitude": 800.0, "frequency_hz": 1.7, "units": "N"},
                                 "p3": {"type": "sine", "amplitude": 500.0, "frequency_hz": 1.7, "units": "N"},
                                 "m2": {"type": "sine", "amplitude": 300.0, "frequency_hz": 1.7, "units": "N m"}}},
        "analysis": {"dt": dt, "duration": 1.5, "integrator": integrator, "estimate_error": False,
                     "kinematics": "small"},  # (the modal solution is the small rotations')
    }


def modal_solution(data: dict, t: np.ndarray) -> np.ndarray:
    """q(t) from rest under p0 sin(W t): sum over the modes of (M, K) of
    phi phi^T p0 / (w^2 - W^2) (sin W t - W / w sin w t); M and K built here from the deck."""
    body = polyhedron(data["body"]["vertices"])
    m = data["body"]["mass"]
    mass = np.zeros((6, 6))
    mass[:3, :3] = m * np.eye(3)
    mass[3:, 3:] = body.inertia(m)
    g = body.centroid
    k = np.zeros((6, 6))
    for el in data["elements"]:
        r = np.array(el["point"]) - g
        d = np.array(el["direction"]) / np.linalg.norm(el["direction"])
        b = np.concatenate([d, np.cross(r, d)])
        k += data["hysteresis"][el["hysteresis"]]["loading"]["kb"] * np.outer(b, b)
    f = data["excitation"]["force"]
    x = np.array(f["point"]) - g
    p0 = np.zeros(6)
    p0[0], p0[2] = f["p1"]["amplitude"], f["p3"]["amplitude"]
    p0[3:] += np.cross(x, p0[:3])
    p0[4] += f["m2"]["amplitude"]
    w2, phi = scipy.linalg.eigh(k, mass)  # mass-normalised
    w, big_w = np.sqrt(w2), 2 * math.pi * f["p1"]["frequency_hz"]
    eta = (phi.T @ p0) / (w2 - big_w ** 2) * (np.sin(big_w * t[:, None]) - big_w / w * np.sin(w * t[:, None]))
    return eta @ phi.T


COLUMNS6 = ("u1_m", "u2_m", "u3_m", "theta1_rad", "theta2_rad", "theta3_rad")


@pytest.mark.parametrize("integrator", ["chang", "newmark"])
def test_second_order_against_the_modal_closed_form(tmp_path, integrator):
    errors = []
    for dt in (2e-3, 1e-3, 5e-4):
        data = linear_scene(dt, integrator)
        res = rbhyst.run(write_deck(tmp_path, data))
        exact = modal_solution(data, res.time)
        got = np.column_stack([res.column(c) for c in COLUMNS6])
        errors.append(max(np.max(np.abs(got[:, j] - exact[:, j])) / np.max(np.abs(exact[:, j])) for j in range(6)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 5e-3 and np.all(np.abs(orders - 2.0) < 0.15), (errors, orders)


def test_the_adaptive_run_is_the_modal_closed_form(tmp_path):
    data = linear_scene(integrator="adaptive")
    res = rbhyst.run(write_deck(tmp_path, data))
    exact = modal_solution(data, res.time)
    for j, c in enumerate(COLUMNS6):
        assert np.max(np.abs(res.column(c) - exact[:, j])) < 1e-6 * np.max(np.abs(exact[:, j])), c


@pytest.mark.parametrize("integrator", ["chang", "newmark", "kr-alpha", "central-difference", "adaptive"])
def test_the_energy_balance_closes_in_space(integrator):
    res = rbhyst.run(DECKS / "cabinet_3d.toml", integrator=integrator, estimate=False)
    assert res.energy_balance < (1e-6 if integrator == "adaptive" else 5e-3), res.energy_balance
    assert res.summary()["energy"]["hysteretic_J"] > 0.0


# ------------------------------------------------------------------ the estimate


def short_sample(tmp_path, seconds: float = 4.0):
    data = rbhyst.load_deck(DECKS / "cabinet_3d.toml").model_dump(mode="python", exclude_unset=True)
    data["analysis"]["duration"] = seconds
    data.pop("output", None)
    for axis in ("x1", "x2", "x3"):
        data["excitation"]["support"][axis]["file"] = str(DECKS / data["excitation"]["support"][axis]["file"])
    return write_deck(tmp_path, data, "cabinet")


def test_the_estimate_is_honest_on_the_sample_deck_in_space(tmp_path):
    res = rbhyst.run(short_sample(tmp_path))
    true, est = true_error(res), estimated(res)
    assert 0.5 <= est / true <= 10.0, (est, true)


@pytest.mark.parametrize("seed", [3, 11])
def test_the_estimate_is_honest_on_a_random_scene_in_space(tmp_path, seed):
    rng = np.random.default_rng(seed)
    turn = rotation_matrix(rng.normal(size=3), rng.uniform(0.2, 1.2))
    data = box_scene(turn)
    data["analysis"]["estimate_error"] = True
    for el in data["elements"]:
        el["point"] = list(np.array(el["point"]) + rng.normal(scale=0.05, size=3))
    res = rbhyst.run(write_deck(tmp_path, data))
    true, est = true_error(res), estimated(res)
    assert 0.5 <= est / true <= 10.0, (est, true)


# ------------------------------------------------------------------ the deck


def test_a_small_sweep_in_space_runs(tmp_path):
    """A deck value swept over two levels: the sweep needs nothing of the plane."""
    path = short_sample(tmp_path, 1.0)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(f'deck = "{path.name}"\n\n[vary]\n"body.mass" = [500.0, 600.0]\n')
    code, out = invoke("sweep", str(sweep), "--workers", "1", "--no-plots", "--out", str(tmp_path / "sweep"))
    assert code == 0, out
    cases = (tmp_path / "sweep" / "cases.csv").read_text().splitlines()
    assert len(cases) == 3 and "peak_u3_m" in cases[0] and "peak_theta1_rad" in cases[0], cases[0]


def sample_by_elements() -> dict:
    """decks/cabinet_3d.toml as a mapping, its isolators written out as the twelve elements they are."""
    deck = rbhyst.load_deck(DECKS / "cabinet_3d.toml")
    data = deck.model_dump(mode="python", exclude_unset=True)
    data.pop("isolators", None)
    data["elements"] = [el.model_dump(mode="python", exclude_unset=True) for el in deck.all_elements]
    return data


MISTAKES = [
    ("mixed coordinates", lambda d: d["elements"][0].update(point=[0.0, 0.0]) or d["elements"][0].pop("vertex"),
     "elements[1].point: List should have at least 3 items"),
    ("zero direction", lambda d: d["elements"][1].update(direction=[0.0, 0.0, 0.0]),
     "elements[2].direction: [0, 0, 0] has no direction"),
    ("angle in space", lambda d: d["elements"][2].update(angle_deg=90.0),
     "elements[3].angle_deg: the deck is in space (3-D)"),
    ("non-SPD inertia", lambda d: d.update(body={
        "mass": 550.0, "mass_centre": [0.4, 0.3, 1.0], "inertia": [[10.0, 0, 0], [0, 10.0, 12.0], [0, 12.0, 10.0]],
        "vertices": [list(v) for v in box_vertices([0.8, 0.6, 2.0], [0.4, 0.3, 1.0])]}),
     "body.inertia: the tensor is not positive definite"),
    ("unsymmetric inertia", lambda d: d.update(body={
        "mass": 550.0, "mass_centre": [0.4, 0.3, 1.0], "inertia": [[10.0, 1.0, 0], [0, 10.0, 0], [0, 0, 10.0]],
        "vertices": [list(v) for v in box_vertices([0.8, 0.6, 2.0], [0.4, 0.3, 1.0])]}),
     "body.inertia: the tensor is not symmetric"),
    ("flat polyhedron", lambda d: d.update(body={"mass": 550.0, "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0],
                                                                             [0, 1, 0]]}),
     "body.vertices: the vertices lie in one plane"),
    ("vertical force in the plane", None, "excitation.force.p3: the deck is in the plane (2-D)"),
    ("direction in the plane", None, "elements[1].direction: the deck is in the plane (2-D)"),
    ("three coordinates in the plane", None, "body.vertices[2]: List should have at most 2 items"),
]


@pytest.mark.parametrize("name, change, words", MISTAKES, ids=[m[0] for m in MISTAKES])
def test_a_deck_mistake_in_space_is_one_line_naming_the_key(tmp_path, name, change, words):
    if change is None:
        data = seed_deck()
        if name == "vertical force in the plane":
            data["excitation"]["force"] = {"p3": {"type": "sine", "amplitude": 1.0, "frequency_hz": 1.0, "units": "N"}}
        elif name == "direction in the plane":
            data["elements"][0]["direction"] = [1.0, 0.0, 0.0]
            data["elements"][0].pop("angle_deg")
        else:
            data["body"]["vertices"][1] = [0.4714, 1.0571, 0.0]
    else:
        data = sample_by_elements()
        for axis in ("x1", "x2", "x3"):
            data["excitation"]["support"][axis]["file"] = str(DECKS / data["excitation"]["support"][axis]["file"])
        change(data)
    code, out = invoke("run", str(write_deck(tmp_path, data)), "--out", str(tmp_path / "out"), "--no-plots")
    errors = [line for line in out.splitlines() if line.startswith("error:")]
    assert code == 2 and len(errors) == 1 and words in errors[0], out


def test_a_body_of_parts_in_space_is_their_parallel_axis_sum():
    """Two boxes as [[body.parts]] (one given by its vertices) are the one box they make up; a
    vertex of the second part is found by part and vertex."""
    data = sample_by_elements()
    data.pop("excitation")
    data["analysis"]["duration"] = 1.0
    data["body"] = {"parts": [{"box": {"size": [0.8, 0.6, 1.0], "centre": [0.4, 0.3, 0.5]}, "mass": 275.0},
                              {"vertices": [list(v) for v in box_vertices([0.8, 0.6, 1.0], [0.4, 0.3, 1.5])],
                               "mass": 275.0}]}
    for el in data["elements"]:
        el["part"] = 1
    data["elements"][0].update(part=2, vertex=8)  # the second box's top corner 4: (0, 0.6, 2)
    system = assemble(parse_deck(data), DECKS)
    whole = polyhedron(box_vertices([0.8, 0.6, 2.0], [0.4, 0.3, 1.0]))
    assert system.body.form == "parts" and system.body.mass == 550.0
    np.testing.assert_allclose(system.body.mass_centre, whole.centroid, atol=1e-12)
    np.testing.assert_allclose(system.body.inertia, whole.inertia(550.0), rtol=0, atol=1e-12 * 550.0)
    np.testing.assert_allclose(system.elements[0].x, np.array([0.0, 0.6, 2.0]) - whole.centroid, atol=1e-12)
    assert system.frame is None  # a box's tensor is diagonal: nothing turns
