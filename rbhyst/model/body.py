"""The rigid body: its mass, mass centre G and polar inertia about G, and its outlines about G.

Three forms (docs/reference/deck.md, "Body"): one uniform polygon (seed eqs. 1-4), several uniform
polygons combined by the parallel-axis theorem, or the properties given directly with an
outline. Downstream, every coordinate is relative to G.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from rbhyst.errors import InputError
from rbhyst.model.geometry import PolygonError, contains, parallel_axis, polygon

if TYPE_CHECKING:  # pragma: no cover
    from rbhyst.model import deck as dk


@dataclass(frozen=True)
class Part:
    """A uniform polygon of the body."""

    vertices: np.ndarray  # (N, 2) relative to the body's G, in the deck's numbering
    mass: float  # kg
    area: float  # m2
    centroid: np.ndarray  # (2,) its own centroid, deck frame
    inertia: float  # polar, about its own centroid, kg m2


@dataclass(frozen=True)
class Body:
    """What the equation of motion needs (m, J about G) and what drawing and elements need."""

    form: Literal["polygon", "parts", "direct"]
    mass: float  # kg
    mass_centre: np.ndarray  # (2,) G in the deck's frame: the origin of every coordinate downstream
    inertia: float  # J_x3 about G, kg m2
    parts: tuple[Part, ...]  # the uniform polygons ("polygon": one; "direct": none)
    outline: np.ndarray | None = None  # "direct": the outline's vertices relative to G
    outline_area: float | None = None  # "direct"

    @property
    def outlines(self) -> list[np.ndarray]:
        """Every polygon to draw, vertices relative to G."""
        return [p.vertices for p in self.parts] if self.parts else [self.outline]

    @property
    def extent(self) -> float:
        """The largest |coordinate| of any vertex about G: the body's size."""
        return max(float(np.max(np.abs(v))) for v in self.outlines)

    def vertex(self, part: int | None, vertex: int) -> np.ndarray:
        """Vertex ``vertex`` (1-based) of part ``part`` (1-based; None: part 1 or the outline),
        relative to G. The deck has checked the indices (deck.vertex_reference_problems)."""
        return self.outlines[(part or 1) - 1][vertex - 1]


def _polygon_or_problem(vertices, key: str, problems: list[str]):
    try:
        return polygon(vertices)
    except PolygonError as err:
        problems.append(f"{key}: {err}")
        return None


def body_from_deck(spec: dk.Body) -> tuple[Body, list[str]]:
    """The body of a validated ``[body]`` table, and notes for the user.

    Raises InputError with one line per polygon that is not simple with positive area.
    """
    problems, notes = [], []
    if spec.form == "direct":
        shape = _polygon_or_problem(spec.vertices, "body.vertices", problems)
        if problems:
            raise InputError(problems)
        g = np.asarray(spec.mass_centre, dtype=float)
        outline = np.asarray(spec.vertices, dtype=float) - g
        body = Body("direct", spec.mass, g, spec.inertia, (), outline, shape.area)
        if not contains(spec.vertices, g):
            notes.append(f"body.mass_centre ({g[0]:.6g}, {g[1]:.6g}) m lies outside the outline "
                         "body.vertices: taken as given")
        # the farthest point of a polygon from G is a vertex: mass inside the outline has J <= m r^2
        r2 = float(np.max(np.sum(outline * outline, axis=1)))
        if spec.inertia > spec.mass * r2:
            notes.append(f"body.inertia {spec.inertia:.6g} kg m2 exceeds the whole mass at the outline's "
                         f"farthest vertex from G ({spec.mass * r2:.6g} kg m2): some mass lies outside "
                         "the outline")
        what = "body.mass_centre is not at the origin"
    else:
        if spec.form == "polygon":
            given = [("body.vertices", spec.vertices, spec.mass)]
        else:
            given = [(f"body.parts[{i}].vertices", p.vertices, p.mass) for i, p in enumerate(spec.parts, start=1)]
        shapes = [_polygon_or_problem(v, key, problems) for key, v, _ in given]
        if problems:
            raise InputError(problems)
        for (key, _, _), shape in zip(given, shapes):
            if shape.reordered:
                notes.append(f"{key} are clockwise: taken in reverse order for eqs. 2-4")
        own = [(m, s.centroid, s.polar_inertia(m)) for (_, _, m), s in zip(given, shapes)]
        mass, g, inertia = parallel_axis(own)
        parts = tuple(Part(np.asarray(v, dtype=float) - g, m, s.area, s.centroid, j)
                      for (_, v, m), s, (_, _, j) in zip(given, shapes, own))
        body = Body(spec.form, mass, g, inertia, parts)
        what = ("body.vertices are not centred on the centroid" if spec.form == "polygon"
                else "body.parts are not centred on their mass centre")
    if np.hypot(*body.mass_centre) > 1e-9 * body.extent:
        notes.append(f"{what}: coordinates shifted by ({-body.mass_centre[0]:.6g}, "
                     f"{-body.mass_centre[1]:.6g}) m so that G is the origin")
    return body, notes


def body_summary(body: Body) -> dict:
    """The ``body`` entry of summary.json (docs/reference/outputs.md; a body in space: docs/explanation/space.md)."""
    if getattr(body, "dimensions", 2) == 3:
        from rbhyst.model.solid import solid_summary

        return solid_summary(body)
    out = {"form": body.form}
    if body.form == "polygon":
        out["area_m2"] = body.parts[0].area
    elif body.form == "direct":
        out["area_m2"] = body.outline_area  # of the outline
    out["mass_kg"] = body.mass
    out["inertia_kgm2"] = body.inertia
    out["mass_centre_m"] = body.mass_centre.tolist()
    if body.form == "polygon":
        out["centroid_m"] = body.mass_centre.tolist()  # a uniform polygon's mass centre is its centroid
        out["vertices_m"] = body.parts[0].vertices.tolist()
    elif body.form == "direct":
        out["vertices_m"] = body.outline.tolist()
    else:
        out["parts"] = [{"mass_kg": p.mass, "area_m2": p.area, "centroid_m": p.centroid.tolist(),
                         "inertia_kgm2": p.inertia, "vertices_m": p.vertices.tolist()} for p in body.parts]
    return out
