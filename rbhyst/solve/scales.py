"""The scale of each output column's family (G's translations with the points', a rotation at the
body's radius of gyration, forces with forces, moments with moments) and the columns a run
leaves at rest against it, to rounding: what the estimate measures a quiet column's error
against (rbhyst.solve.estimate) and what the console and the report print as 0."""

from __future__ import annotations

import math

import numpy as np

from rbhyst.model.system import System
from rbhyst.solve.history import estimate_columns

#: a column whose reference stays below this fraction of its family's scale is at rest: its error
#: is measured against the family's scale (the rotation of a symmetric scene, a cross acceleration)
AT_REST = 1e-9


def to_length(keys, system: System) -> np.ndarray:
    """What turns each column into its family's translational measure: the radius of gyration
    for a rotation or angular acceleration (sqrt(J / m), the rotation's mass over the first
    translation's), its inverse for a moment; 1 for the others."""
    coords = system.coordinates
    masses = system.mass
    frame = getattr(system, "frame", None)
    if frame is not None:  # the columns are in the deck's axes: the diagonal of M there
        masses = np.einsum("ij,j,ij->i", frame, system.mass, frame)
    mass = next((masses[j] for j, c in enumerate(coords) if not c.rotation), None)
    factor = {}
    for j, c in enumerate(coords):
        if c.rotation and mass is not None:
            rg = math.sqrt(masses[j] / mass)
            factor.update({c.key("d"): rg, c.key("at"): rg, c.key("R"): 1.0 / rg})
    return np.array([factor.get(k, 1.0) for k in keys])


def family_scales(peak: np.ndarray, keys, families, system: System) -> np.ndarray:
    """Each column's family's scale (error_scales): the family's largest peak in its measure."""
    length = to_length(keys, system)
    index: dict = {}
    family = np.array([index.setdefault(f, len(index)) for f in families], dtype=np.intp)
    top = np.zeros(len(index))
    np.maximum.at(top, family, peak * length)  # each family's largest peak, in its measure
    return top[family] / length


def at_rest_columns(result) -> list[str]:
    """The CSV columns a run leaves at rest: those whose peak over every step stays below
    AT_REST of its family's scale (family_scales: G's motion with the points', a rotation at
    the radius of gyration, forces with forces; the elements' deformations among themselves),
    the rounding a symmetric scene leaves across its excitation (1e-17 m beside 1e-3 m): printed
    as 0, never as a response. In the order of the columns; none without a layout."""
    if result.layout is None:
        return []
    layout = result.layout
    index = {name: i for i, name in enumerate(layout.names)}
    cols = estimate_columns(layout) + [(f"e{k}_u", index[f"e{k}_u_m"], "eu")
                                       for k in range(1, layout.system.n_output_elements + 1)]
    keys, columns, families = [k for k, _, _ in cols], [c for _, c, _ in cols], [f for _, _, f in cols]
    e = result.extremes
    peaks = np.maximum(np.abs(e.max[columns]), np.abs(e.min[columns]))
    scales = family_scales(peaks, keys, families, result.system)
    return [layout.names[c] for c, p, f in sorted(zip(columns, peaks, scales)) if p < AT_REST * f]
