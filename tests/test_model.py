"""Kinematics and assembly (seed eqs. 5-13)."""

import math

import numpy as np
import pytest

from rbhyst.model.deck import parse_deck
from rbhyst.errors import InputError
from rbhyst.model.system import assemble, b_vector
from conftest import SEED_MASS, square_linear_deck


@pytest.mark.parametrize("x1, x2, angle", [(0.47, -0.94, 0.0), (-0.73, 0.26, 90.0), (0.3, 0.8, 37.0),
                                           (-1.2, -0.4, 211.0)])
def test_element_deformation_matches_an_exact_small_rigid_rotation(x1, x2, angle):
    a = math.radians(angle)
    direction = np.array([math.cos(a), math.sin(a)])
    b = b_vector(x1, x2, a)
    for theta in (1e-3, 1e-4, 1e-5):
        u = np.array([0.002, -0.001])
        rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
        exact = (rot @ [x1, x2] - [x1, x2] + u) @ direction
        linear = b @ np.array([u[0], u[1], theta])
        # eqs. 7-8 are the small-angle form: the difference is second order in theta
        assert abs(exact - linear) <= 0.51 * theta**2 * math.hypot(x1, x2) + 1e-15


def test_force_acts_back_with_the_moment_of_eq_11():
    x1, x2, a = 0.4, -0.9, math.radians(30.0)
    f = 1234.0
    b = b_vector(x1, x2, a)
    fx, fy = f * math.cos(a), f * math.sin(a)
    np.testing.assert_allclose(b * f, [fx, fy, x1 * fy - x2 * fx])


def test_decoupled_square_has_the_expected_mass_and_stiffness(tmp_path):
    k = 2.0e5
    system = assemble(parse_deck(square_linear_deck(k=k, mass=500.0, side=1.0)), tmp_path)
    np.testing.assert_allclose(system.mass, [500.0, 500.0, 500.0 / 6.0])
    np.testing.assert_allclose(system.K0, np.diag([2 * k, 2 * k, k]), atol=1e-9 * k)


def test_seed_scene_assembles_with_counted_elements(tmp_path):
    from conftest import seed_deck

    system = assemble(parse_deck(seed_deck()), tmp_path)
    assert system.mass[2] == pytest.approx(297.7294, abs=1e-4)
    assert system.mass[0] == SEED_MASS
    assert system.n_output_elements == 8
    # the shear isolators under P1 and P2 both have b = (0, 1, 0.4714): one kernel row of 4
    assert system.bvec.shape == (3, 3)
    np.testing.assert_array_equal(system.mult, [2, 4, 2])
    assert [el.row for el in system.elements] == [0, 1, 2, 1]
    assert system.row_elements(1) == [3, 4, 7, 8]
    cols = system.expand(np.array([[10.0, 20.0, 30.0]]))
    np.testing.assert_array_equal(cols, [[10, 10, 20, 20, 30, 30, 20, 20]])


@pytest.mark.parametrize("elements, free", [
    ([{"vertex": 1, "angle_deg": 0.0}, {"vertex": 2, "angle_deg": 0.0}, {"vertex": 3, "angle_deg": 0.0}],
     "translation along 90 deg"),
    ([{"point": [0.0, 0.0], "angle_deg": 0.0}, {"point": [0.0, 0.0], "angle_deg": 90.0}],
     "rotation about the mass centre G"),
    ([{"vertex": 1, "angle_deg": 90.0}, {"vertex": 1, "angle_deg": 0.0}], "rotation about the point"),
])
def test_an_unrestrained_direction_is_named(tmp_path, elements, free):
    deck = square_linear_deck()
    deck["elements"] = [dict(e, hysteresis="lin") for e in elements]
    with pytest.raises(InputError, match=free):
        assemble(parse_deck(deck), tmp_path)
