"""model.png of a body in space: three orthographic views (top, front, side) and an isometric
one, each with the body's edges, its mass centre G and its elements along their lines of action."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.report._labels import Labels
from rbhyst.report._style import styled, write_png

#: (title, screen x axis, screen y axis) of each orthographic view: unit vectors in the deck's frame
VIEWS = (("top (from +x3)", (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), "x1 [m]", "x2 [m]"),
         ("front (from -x2)", (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), "x1 [m]", "x3 [m]"),
         ("side (from +x1)", (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), "x2 [m]", "x3 [m]"))


def isometric_axes() -> tuple[np.ndarray, np.ndarray]:
    """Screen x and y of an isometric view from the side of +x1, -x2, +x3, x3 up."""
    eye = np.array([1.0, -1.0, 1.0]) / np.sqrt(3.0)
    right = np.cross([0.0, 0.0, 1.0], eye)
    right /= np.linalg.norm(right)
    return right, np.cross(eye, right)


def _draw(ax, result, sx, sy, labels: Labels | None = None) -> None:
    """Edges, G, elements (and dampers) projected on the screen axes sx, sy; with ``labels``, each
    named through it (placed later, clear of each other and of the drawing)."""
    system = result.system
    body = system.body
    sx, sy = np.asarray(sx), np.asarray(sy)
    placer = labels if labels is not None else Labels()  # (unnamed views: what is drawn, not placed)
    for vertices, edges in zip(body.outlines, body.edge_lists):
        for a, b in edges:
            p = vertices[[a, b]]
            ax.plot(p @ sx, p @ sy, color="0.25", lw=1.0, zorder=2)
            placer.line(np.column_stack([p @ sx, p @ sy]))
    ax.plot(0.0, 0.0, "k+", ms=9, zorder=3)
    placer.point(0.0, 0.0, 4.5)
    size = max(float(np.ptp(np.vstack(body.outlines), axis=0).max()), 1e-12)
    length = 0.18 * size
    k = 1
    for el in system.elements:
        x, d = np.asarray(el.x), np.asarray(el.direction)
        side = 1.0 if float(x @ d) >= 0.0 else -1.0  # outward along its line, away from G
        end = x + side * length * d
        seg = np.array([x, end])
        ax.plot(seg @ sx, seg @ sy, color="C0", lw=2.2, solid_capstyle="round", zorder=4)
        ax.plot(end @ sx, end @ sy, marker="s", color="C0", ms=4, zorder=4)
        placer.line(np.column_stack([seg @ sx, seg @ sy]))
        placer.point(end @ sx, end @ sy, 2.5)
        name = f"e{k}" if el.count == 1 else f"e{k}-{k + el.count - 1}"
        out = (end - x) @ np.column_stack([sx, sy])  # beyond its free end, on the screen
        placer.add(name, (end @ sx, end @ sy), tuple(out), 3.0, fontsize=7, color="C0")
        k += el.count
    for dp in system.dampers:
        x, d = np.asarray(dp.x), np.asarray(dp.direction)
        side = 1.0 if float(x @ d) >= 0.0 else -1.0
        seg = np.array([x, x + side * 0.8 * length * d])
        ax.plot(seg @ sx, seg @ sy, color="C2", lw=1.4, ls="--", zorder=4)
        placer.line(np.column_stack([seg @ sx, seg @ sy]))
    for name, p in result.layout.points:
        ax.plot(p @ sx, p @ sy, marker="o", color="C3", ms=4, zorder=5)
        placer.point(p @ sx, p @ sy, 3.0)
        placer.add(name, (p @ sx, p @ sy), (p @ sx or 1.0, p @ sy or 1.0), 3.0, fontsize=7, color="C3")
    placer.add("G", (0.0, 0.0), (1.0, -1.0), 5.0, fontsize=8)
    ax.set_aspect("equal")
    ax.margins(0.12)


@styled
def plot_body_3d(result, path: Path):
    """The body in space, its mass centre G (the origin: coordinates are relative to it), its
    elements drawn from their points outward along their lines of action (a square at the support)
    and the points of interest: a large isometric view, named, beside three orthographic ones
    (top, front, side). Returns the figure (saved to ``path``)."""
    from matplotlib.figure import Figure

    system = result.system
    fig = Figure(figsize=(9.0, 8.5))
    grid = fig.add_gridspec(3, 2, width_ratios=(1.7, 1.0))
    for k, (title, sx, sy, xl, yl) in enumerate(VIEWS):
        ax = fig.add_subplot(grid[k, 1])
        _draw(ax, result, sx, sy)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    ax = fig.add_subplot(grid[:, 0])
    right, up = isometric_axes()
    labels = Labels()
    _draw(ax, result, right, up, labels)
    ax.set_title("isometric", fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    for spine in ax.spines.values():
        spine.set_visible(False)
    j = np.linalg.eigvalsh(system.body.inertia)
    fig.suptitle(f"{system.title or 'Model'}\nm = {system.body.mass:.6g} kg, principal J = "
                 f"{', '.join(f'{x:.4g}' for x in j)} kg m² about G; coordinates from G", fontsize=9)
    fig.tight_layout()
    # the deck's axes as a small triad in the panel's corner; the labels are placed clear of it
    corner = np.array([0.06, 0.05])
    triad = []
    for k, e in enumerate(np.eye(3)):
        v = np.array([e @ right, e @ up]) * 0.06
        ax.annotate("", xy=corner + v, xytext=corner, xycoords="axes fraction",
                    arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 0.8})
        triad.append(ax.annotate(f"x{k + 1}", corner + 1.45 * v, xycoords="axes fraction", fontsize=7,
                                 color="0.3", ha="center", va="center"))
    labels.place(fig, ax, triad)
    write_png(fig, path)
    return fig
