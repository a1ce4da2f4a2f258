"""Properties of a polygonal rigid body from its vertices (seed eqs. 1-4), and of several.

Pure functions: one uniform polygon (``polygon``), a body of uniform polygons by the
parallel-axis theorem (``composite``, ``parallel_axis``), and whether a point lies in a polygon.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Sequence

import numpy as np


class PolygonError(ValueError):
    """The vertices do not describe a simple polygon with positive area."""


@dataclass(frozen=True)
class Polygon:
    """A simple polygon about its centroid G, vertices counterclockwise."""

    vertices: np.ndarray  # (N, 2), relative to the centroid
    area: float  # A, eq. 2
    centroid: np.ndarray  # (2,), of the vertices as given
    i_x1: float  # about the x1 axis through G, eq. 3
    i_x2: float  # about the x2 axis through G, eq. 4
    reordered: bool  # the input was clockwise and was reversed

    def polar_inertia(self, mass: float) -> float:
        """J_x3 = m / A (I_x1 + I_x2), eq. 1."""
        return mass / self.area * (self.i_x1 + self.i_x2)


def _cross_terms(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x, y = v[:, 0], v[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    return x * yn - y * xn, (x, xn), (y, yn)


def signed_area(v: np.ndarray) -> float:
    """Eq. 2: positive for counterclockwise vertices."""
    cr, _, _ = _cross_terms(v)
    return 0.5 * float(cr.sum())


def second_moments(v: np.ndarray) -> tuple[float, float]:
    """(I_x1, I_x2) about the origin, eqs. 3-4, for counterclockwise vertices."""
    cr, (x, xn), (y, yn) = _cross_terms(v)
    i_x1 = float((cr * (y * y + y * yn + yn * yn)).sum()) / 12.0
    i_x2 = float((cr * (x * x + x * xn + xn * xn)).sum()) / 12.0
    return i_x1, i_x2


def centroid(v: np.ndarray) -> np.ndarray:
    cr, (x, xn), (y, yn) = _cross_terms(v)
    a = 0.5 * cr.sum()
    return np.array([((x + xn) * cr).sum(), ((y + yn) * cr).sum()]) / (6.0 * a)


def _segments_cross(p1, p2, q1, q2) -> bool:
    """True where closed segments p1p2 and q1q2 share a point."""

    def orient(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    def on_segment(a, b, c):
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    o1, o2 = orient(p1, p2, q1), orient(p1, p2, q2)
    o3, o4 = orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 != o2 and o3 != o4 and o1 * o2 <= 0 and o3 * o4 <= 0:
        return True
    return (
        (o1 == 0 and on_segment(p1, p2, q1))
        or (o2 == 0 and on_segment(p1, p2, q2))
        or (o3 == 0 and on_segment(q1, q2, p1))
        or (o4 == 0 and on_segment(q1, q2, p2))
    )


def check_simple(v: np.ndarray) -> None:
    """Raise PolygonError for fewer than 3 vertices, repeats or crossing edges."""
    n = len(v)
    if n < 3:
        raise PolygonError(f"a polygon needs at least 3 vertices, got {n}")
    for i in range(n):
        for j in range(i + 1, n):
            if np.array_equal(v[i], v[j]):
                raise PolygonError(f"vertices {i + 1} and {j + 1} coincide at {v[i].tolist()}")
    for i in range(n):
        for j in range(i + 1, n):
            # adjacent edges share a vertex by construction
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if _segments_cross(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n]):
                raise PolygonError(
                    f"edges P{i + 1}-P{(i + 1) % n + 1} and P{j + 1}-P{(j + 1) % n + 1} intersect: "
                    "the polygon is self-intersecting"
                )


def polygon(vertices) -> Polygon:
    """Validate the vertices and compute A, G, I_x1, I_x2 (eqs. 2-4) about G.

    Clockwise input is taken in reverse order for eqs. 2-4 (``reordered`` is set
    so the caller can warn); the returned vertices keep the input's numbering, so
    ``vertex = k`` in a deck always means the k-th vertex listed, shifted to G.
    """
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 2:
        raise PolygonError("vertices must be a list of [x1, x2] pairs")
    shape = _polygon(len(v), v.tobytes())
    return dataclasses.replace(shape, vertices=shape.vertices.copy(), centroid=shape.centroid.copy())


@functools.lru_cache(maxsize=64)
def _polygon(n: int, vertices: bytes) -> Polygon:
    """polygon() of the n vertices with these bytes, kept for the next body with the same
    outline: a sweep builds it for every case, a third of the time of building a case's scene
    (the check that no two edges cross, mostly). A failed check is not kept: it raises again."""
    v = np.frombuffer(vertices, dtype=float).reshape(n, 2)
    check_simple(v)
    a = signed_area(v)
    scale = max(float(np.ptp(v[:, 0])), float(np.ptp(v[:, 1])), 1e-300)
    if abs(a) <= 1e-12 * scale * scale:
        raise PolygonError("the polygon has zero area")
    reordered = a < 0.0
    ccw = v[::-1] if reordered else v
    g = centroid(ccw)
    vg = v - g
    i_x1, i_x2 = second_moments(ccw - g)
    a = abs(a)
    return Polygon(vertices=vg, area=a, centroid=g, i_x1=i_x1, i_x2=i_x2, reordered=reordered)


def parallel_axis(items: Sequence[tuple[float, np.ndarray, float]]) -> tuple[float, np.ndarray, float]:
    """(m_i, c_i, J_i about c_i) of rigid pieces -> (m, G, J about G) of the whole.

    m = sum m_i, G = sum (m_i / m) c_i, J = sum (J_i + m_i |c_i - G|^2) (parallel-axis
    theorem). Masses add where pieces overlap. Written so that one piece returns its own
    m, c, J bit for bit (weight 1.0, distance 0.0).
    """
    m = 0.0
    for mi, _, _ in items:
        m += mi
    g = np.zeros(2)
    for mi, ci, _ in items:
        g = g + (mi / m) * np.asarray(ci, dtype=float)
    j = 0.0
    for mi, ci, ji in items:
        d = np.asarray(ci, dtype=float) - g
        j += ji + mi * float(d @ d)
    return m, g, j


def composite(parts: Sequence[tuple[object, float]]) -> tuple[float, np.ndarray, float]:
    """Mass, mass centre (in the vertices' frame) and polar inertia about it of a body made
    of uniform polygons ``(vertices, mass)``, each by eqs. 1-4; they may overlap.

    Raises PolygonError for a part that is not a simple polygon with positive area.
    """
    items = []
    for vertices, mass in parts:
        p = polygon(vertices)
        items.append((float(mass), p.centroid, p.polar_inertia(float(mass))))
    return parallel_axis(items)


def contains(vertices, point) -> bool:
    """True where ``point`` lies inside the simple polygon ``vertices`` or on its boundary."""
    v = np.asarray(vertices, dtype=float)
    x, y = float(point[0]), float(point[1])
    n = len(v)
    inside = False
    for i in range(n):
        (x0, y0), (x1, y1) = v[i], v[(i + 1) % n]
        # on this edge: collinear and within its box
        if (abs((x1 - x0) * (y - y0) - (y1 - y0) * (x - x0)) <= 1e-12 * (abs(x1 - x0) + abs(y1 - y0)) ** 2
                and min(x0, x1) <= x <= max(x0, x1) and min(y0, y1) <= y <= max(y0, y1)):
            return True
        # ray casting along +x1: count the edges crossed (half-open in x2, so a vertex counts once)
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside
