import numpy as np
import pytest

from rbhyst.model import geometry
from rbhyst.model.geometry import PolygonError, polygon
from conftest import SEED_MASS, SEED_VERTICES


def test_seed_body_area_and_inertia():
    body = polygon(SEED_VERTICES)
    assert body.area == pytest.approx(1.68, abs=1e-12)
    assert body.polar_inertia(SEED_MASS) == pytest.approx(297.7294, abs=1e-4)


def test_rectangle_against_textbook_formulas():
    b, h, m = 2.0, 0.5, 10.0
    body = polygon([[0, 0], [b, 0], [b, h], [0, h]])
    assert body.area == pytest.approx(b * h)
    np.testing.assert_allclose(body.centroid, [b / 2, h / 2])
    assert body.i_x1 == pytest.approx(b * h**3 / 12)
    assert body.i_x2 == pytest.approx(h * b**3 / 12)
    assert body.polar_inertia(m) == pytest.approx(m * (b * b + h * h) / 12)
    np.testing.assert_allclose(body.vertices.mean(axis=0), 0.0, atol=1e-15)


def test_clockwise_input_is_reordered_and_keeps_its_numbering():
    ccw = polygon(SEED_VERTICES)
    cw = polygon(SEED_VERTICES[::-1])
    assert cw.reordered and not ccw.reordered
    assert cw.area == pytest.approx(ccw.area)
    assert cw.polar_inertia(1.0) == pytest.approx(ccw.polar_inertia(1.0))
    # vertex k of the input stays vertex k
    np.testing.assert_allclose(cw.vertices[0], ccw.vertices[-1])


def test_inertia_is_invariant_under_translation_and_rotation():
    rng = np.random.default_rng(3)
    v = np.array(SEED_VERTICES)
    base = polygon(v).polar_inertia(SEED_MASS)
    for _ in range(5):
        ang = rng.uniform(0, 2 * np.pi)
        rot = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
        moved = v @ rot.T + rng.uniform(-5, 5, 2)
        assert polygon(moved).polar_inertia(SEED_MASS) == pytest.approx(base, rel=1e-12)


@pytest.mark.parametrize("verts, words", [
    ([[0, 0], [1, 0], [2, 0]], "zero area"),
    ([[0, 0], [1, 0], [1, 1], [1, 0]], "coincide"),
    ([[0, 0], [1, 1], [1, 0], [0, 1]], "self-intersecting"),
    ([[0, 0], [1, 0]], "at least 3"),
])
def test_degenerate_polygons_are_errors(verts, words):
    with pytest.raises(PolygonError, match=words):
        polygon(verts)


def test_a_polygon_built_again_is_the_same_and_its_own():
    """polygon() keeps what it built for the next body with the same outline (a sweep's cases):
    the same numbers to the bit, in arrays that are the caller's to change; a vertex that
    differs in its last bit, or a -0.0 for a 0.0, is another outline."""
    verts = [[0.0, 0.0], [1.2, 0.0], [1.2, 0.7], [0.3, 1.1]]
    first = polygon(verts)
    first.vertices[0] = 99.0
    first.centroid[:] = -1.0
    again = polygon(np.array(verts))
    assert again.vertices[0, 0] != 99.0 and again.centroid[0] != -1.0
    fresh = geometry._polygon.__wrapped__(4, np.array(verts, dtype=float).tobytes())
    assert np.array_equal(again.vertices, fresh.vertices) and np.array_equal(again.centroid, fresh.centroid)
    assert (again.area, again.i_x1, again.i_x2) == (fresh.area, fresh.i_x1, fresh.i_x2)
    nudged = [list(v) for v in verts]
    nudged[2][0] = np.nextafter(1.2, 2.0)
    built = geometry._polygon.cache_info().misses
    polygon(verts)
    polygon(nudged)
    polygon([[-0.0, 0.0]] + verts[1:])
    assert geometry._polygon.cache_info().misses == built + 2
