"""The rigid body in space: uniform convex polyhedra (a box is one), their mass properties, and
the body a three-dimensional deck describes.

A polyhedron is the convex hull of its vertices (scipy.spatial.ConvexHull). Its volume, centroid
and second moments are exact: the hull is split into tetrahedra from an interior point to each
of its boundary triangles, and a tetrahedron of vertices p0..p3 and volume V has

    int x dV = V s / 4,    int x x^T dV = V / 20 (sum_k p_k p_k^T + s s^T),    s = sum_k p_k,

so that, with density rho = m / V and C = rho int (x - G)(x - G)^T dV about the centroid G,
the inertia tensor is J = tr(C) I - C. Several parts combine by the parallel-axis theorem,
J = sum (J_k + m_k (|d_k|^2 I - d_k d_k^T)), d_k = c_k - G.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from rbhyst.errors import InputError

if TYPE_CHECKING:  # pragma: no cover
    from rbhyst.model import deck as dk


class PolyhedronError(ValueError):
    """Vertices that span no volume."""


@dataclass(frozen=True)
class Polyhedron:
    """A uniform convex polyhedron: volume, centroid, second moment per unit mass about the
    centroid, and its boundary for drawing."""

    vertices: np.ndarray  # (N, 3) as given
    volume: float  # m3
    centroid: np.ndarray  # (3,)
    gyration: np.ndarray  # (3, 3) J / m about the centroid, m2
    triangles: np.ndarray  # (T, 3) vertex indices of the hull's boundary triangles
    inside: tuple[int, ...]  # 0-based indices of vertices that are not corners of the hull

    def inertia(self, mass: float) -> np.ndarray:
        """The inertia tensor about the centroid (kg m2) of this shape of uniform ``mass``."""
        return mass * self.gyration

    @property
    def edges(self) -> list[tuple[int, int]]:
        """The hull's edges (vertex index pairs) between faces that are not coplanar: what a
        drawing shows."""
        tri = self.triangles
        p = self.vertices
        normals = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        seen: dict[tuple[int, int], list[int]] = {}
        for t, (a, b, c) in enumerate(tri):
            for e in ((a, b), (b, c), (c, a)):
                seen.setdefault((min(e), max(e)), []).append(t)
        out = []
        for e, faces in seen.items():
            if len(faces) != 2 or abs(abs(float(normals[faces[0]] @ normals[faces[1]])) - 1.0) > 1e-9:
                out.append((int(e[0]), int(e[1])))
        return out


def box_vertices(size, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(8, 3) the corners of a box: its bottom face (least x3) counterclockwise seen from +x3,
    starting at the corner of least x1 and x2, then the top face in the same order."""
    a = 0.5 * np.asarray(size, dtype=float)
    c = np.asarray(centre, dtype=float)
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    return np.array([c + a * np.array([s1, s2, s3]) for s3 in (-1, 1) for s1, s2 in corners])


def second_moments(p: np.ndarray, triangles: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume, first moment int x dV, second moment int x x^T dV) of the convex solid bounded by
    ``triangles`` of the points p, by tetrahedra from the mean of its corners (inside a convex
    solid); each tetrahedron's volume taken positive, so no orientation of the triangles is needed."""
    o = p[np.unique(triangles)].mean(axis=0)
    volume, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    for a, b, c in triangles:
        q = np.array([o, p[a], p[b], p[c]])
        v = abs(float(np.linalg.det(q[1:] - q[0]))) / 6.0
        s = q.sum(axis=0)
        volume += v
        first += v * s / 4.0
        second += v / 20.0 * (q.T @ q + np.outer(s, s))
    return volume, first, second


def polyhedron(vertices) -> Polyhedron:
    """The uniform convex polyhedron whose corners are ``vertices`` (their convex hull).

    Raises PolyhedronError where they span no volume (fewer than four, or all in one plane)."""
    from scipy.spatial import ConvexHull, QhullError

    p = np.asarray(vertices, dtype=float)
    if len(p) < 4:
        raise PolyhedronError(f"{len(p)} vertices span no volume: a polyhedron needs at least four")
    try:
        hull = ConvexHull(p)
    except QhullError:
        raise PolyhedronError("the vertices lie in one plane (or on one line): they span no volume") from None
    volume, first, second = second_moments(p, hull.simplices)
    size = float(np.max(np.ptp(p, axis=0)))
    if not volume > 1e-12 * size ** 3:
        raise PolyhedronError("the vertices span no volume")
    centroid = first / volume
    c = second / volume - np.outer(centroid, centroid)  # per unit mass, about the centroid
    gyration = np.trace(c) * np.eye(3) - c
    inside = tuple(int(i) for i in sorted(set(range(len(p))) - set(int(k) for k in hull.vertices)))
    return Polyhedron(p, volume, centroid, 0.5 * (gyration + gyration.T), np.asarray(hull.simplices), inside)


def parallel_axis3(items) -> tuple[float, np.ndarray, np.ndarray]:
    """(m_i, c_i, J_i about c_i) of rigid pieces in space -> (m, G, J about G) of the whole:
    J = sum (J_i + m_i (|d_i|^2 I - d_i d_i^T)), d_i = c_i - G."""
    m = sum(mi for mi, _, _ in items)
    g = np.zeros(3)
    for mi, ci, _ in items:
        g = g + (mi / m) * np.asarray(ci, dtype=float)
    j = np.zeros((3, 3))
    for mi, ci, ji in items:
        d = np.asarray(ci, dtype=float) - g
        j = j + np.asarray(ji, dtype=float) + mi * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return m, g, j


@dataclass(frozen=True)
class SolidPart:
    """A uniform convex polyhedron of the body."""

    vertices: np.ndarray  # (N, 3) relative to the body's G, in the deck's numbering
    mass: float  # kg
    volume: float  # m3
    centroid: np.ndarray  # (3,) its own centroid, deck frame
    inertia: np.ndarray  # (3, 3) about its own centroid, kg m2
    edges: tuple[tuple[int, int], ...]  # what a drawing shows
    kind: str = "polyhedron"  # or "box"


@dataclass(frozen=True)
class Solid:
    """A rigid body in space: what the equation of motion needs (m, the inertia tensor J about G)
    and what drawing and elements need; the counterpart of rbhyst.model.body.Body."""

    form: Literal["polyhedron", "box", "parts", "direct"]
    mass: float  # kg
    mass_centre: np.ndarray  # (3,) G in the deck's frame
    inertia: np.ndarray  # (3, 3) about G, deck axes, kg m2
    parts: tuple[SolidPart, ...]
    outline: np.ndarray | None = None  # "direct": the outline's vertices relative to G
    outline_edges: tuple[tuple[int, int], ...] = ()
    dimensions: int = 3

    @property
    def outlines(self) -> list[np.ndarray]:
        """Every polyhedron's vertices, relative to G."""
        return [p.vertices for p in self.parts] if self.parts else [self.outline]

    @property
    def edge_lists(self) -> list[tuple[tuple[int, int], ...]]:
        """The edges of each of :attr:`outlines`, for drawing."""
        return [p.edges for p in self.parts] if self.parts else [self.outline_edges]

    @property
    def extent(self) -> float:
        """The largest |coordinate| of any vertex about G: the body's size."""
        return max(float(np.max(np.abs(v))) for v in self.outlines)

    def vertex(self, part: int | None, vertex: int) -> np.ndarray:
        """Vertex ``vertex`` (1-based) of part ``part`` (1-based; None: part 1 or the outline),
        relative to G."""
        return self.outlines[(part or 1) - 1][vertex - 1]


def _shape(vertices, box, key: str, problems: list[str], notes: list[str]):
    """(vertices, Polyhedron, kind) of a [body] or part entry; None with a problem."""
    if box is not None:
        vertices, kind, key = box_vertices(box.size, box.centre), "box", key.rsplit(".", 1)[0] + ".box"
    else:
        kind = "polyhedron"
    try:
        shape = polyhedron(vertices)
    except PolyhedronError as err:
        problems.append(f"{key}: {err}")
        return None
    if shape.inside:
        notes.append(f"{key}: vertices {', '.join(f'P{i + 1}' for i in shape.inside)} are not corners of their "
                     "convex hull (inside it or on a face or edge): the body is the hull")
    return np.asarray(vertices, dtype=float), shape, kind


def inertia_problems(j) -> list[str]:
    """What keeps a given 3 x 3 inertia tensor from being one (symmetric positive definite), as
    'body.inertia: ...' lines."""
    j = np.asarray(j, dtype=float)
    if not np.allclose(j, j.T, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(j)))):
        return ["body.inertia: the tensor is not symmetric (J12 = J21, J13 = J31, J23 = J32)"]
    lam = np.linalg.eigvalsh(j)
    if not lam[0] > 1e-12 * max(float(lam[-1]), 0.0):
        return [f"body.inertia: the tensor is not positive definite (principal moments {', '.join(f'{x:.6g}' for x in lam)} "
                "kg m2): every one must be > 0"]
    return []


def solid_from_deck(spec: "dk.Body") -> tuple[Solid, list[str]]:
    """The body of a validated ``[body]`` table in space, and notes for the user.

    Raises InputError with one line per shape that spans no volume, or an inertia tensor that is
    not symmetric positive definite."""
    problems, notes = [], []
    if spec.form == "direct":
        problems += inertia_problems(spec.inertia)
        made = _shape(spec.vertices, None, "body.vertices", problems, notes)
        if problems:
            raise InputError(problems)
        g = np.asarray(spec.mass_centre, dtype=float)
        j = np.asarray(spec.inertia, dtype=float)
        body = Solid("direct", spec.mass, g, 0.5 * (j + j.T), (), made[0] - g, tuple(made[1].edges))
        what = "body.mass_centre is not at the origin"
    else:
        if spec.parts is not None:
            given = [(f"body.parts[{i}].vertices", p.vertices, p.box, p.mass) for i, p in enumerate(spec.parts, start=1)]
        else:
            given = [("body.vertices", spec.vertices, spec.box, spec.mass)]
        shapes = [_shape(v, b, key, problems, notes) for key, v, b, _ in given]
        if problems:
            raise InputError(problems)
        own = [(m, s.centroid, s.inertia(m)) for (_, _, _, m), (_, s, _) in zip(given, shapes)]
        mass, g, j = parallel_axis3(own)
        parts = tuple(SolidPart(v - g, m, s.volume, s.centroid, ji, tuple(s.edges), kind)
                      for (_, _, _, m), (v, s, kind), (_, _, ji) in zip(given, shapes, own))
        form = "parts" if spec.parts is not None else parts[0].kind
        body = Solid(form, mass, g, j, parts)
        what = ("body.parts are not centred on their mass centre" if spec.parts is not None
                else "the body is not centred on its centroid")
    if float(np.linalg.norm(body.mass_centre)) > 1e-9 * body.extent:
        shift = ", ".join(f"{-x + 0.0:.6g}" for x in body.mass_centre)
        notes.append(f"{what}: coordinates shifted by ({shift}) m so that G is the origin")
    return body, notes


def solid_summary(body: Solid) -> dict:
    """The ``body`` entry of summary.json for a body in space (docs/explanation/space.md)."""
    out = {"form": body.form, "mass_kg": body.mass, "inertia_kgm2": body.inertia.tolist(),
           "mass_centre_m": body.mass_centre.tolist()}
    lam, vec = np.linalg.eigh(body.inertia)
    out["principal_inertia_kgm2"] = lam.tolist()
    out["principal_axes"] = vec.T.tolist()  # each row an axis, deck frame
    if body.form == "direct":
        out["vertices_m"] = body.outline.tolist()
    elif body.form == "parts":
        out["parts"] = [{"kind": p.kind, "mass_kg": p.mass, "volume_m3": p.volume, "centroid_m": p.centroid.tolist(),
                         "inertia_kgm2": p.inertia.tolist(), "vertices_m": p.vertices.tolist()} for p in body.parts]
    else:
        out["volume_m3"] = body.parts[0].volume
        out["vertices_m"] = body.parts[0].vertices.tolist()
    return out
