"""model.png of a body in space: three orthographic views (top, front, side) and an isometric
one, each with the body's edges, its mass centre G and its elements along their lines of action."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.report._style import styled, subplots, write_png

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


def _draw(ax, result, sx, sy, label: bool) -> None:
    """Edges, G, elements (and dampers) projected on the screen axes sx, sy."""
    system = result.system
    body = system.body
    sx, sy = np.asarray(sx), np.asarray(sy)
    for vertices, edges in zip(body.outlines, body.edge_lists):
        for a, b in edges:
            p = vertices[[a, b]]
            ax.plot(p @ sx, p @ sy, color="0.25", lw=1.0, zorder=2)
    ax.plot(0.0, 0.0, "k+", ms=9, zorder=3)
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
        if label:
            name = f"e{k}" if el.count == 1 else f"e{k}-{k + el.count - 1}"
            tip = x + side * 1.25 * length * d
            ax.annotate(name, (tip @ sx, tip @ sy), fontsize=6, color="C0", ha="center", va="center", zorder=5)
        k += el.count
    for dp in system.dampers:
        x, d = np.asarray(dp.x), np.asarray(dp.direction)
        side = 1.0 if float(x @ d) >= 0.0 else -1.0
        seg = np.array([x, x + side * 0.8 * length * d])
        ax.plot(seg @ sx, seg @ sy, color="C2", lw=1.4, ls="--", zorder=4)
    g = result.layout.points
    for name, p in g:
        ax.plot(p @ sx, p @ sy, marker="o", color="C3", ms=4, zorder=5)
        if label:
            ax.annotate(name, (p @ sx, p @ sy), xytext=(4, 4), textcoords="offset points", fontsize=6.5, color="C3")
    if label:
        ax.annotate("G", (0.0, 0.0), xytext=(5, -9), textcoords="offset points", fontsize=8)
    ax.set_aspect("equal")
    ax.margins(0.12)


@styled
def plot_body_3d(result, path: Path):
    """The body in space, its mass centre G (the origin: coordinates are relative to it), its
    elements drawn from their points outward along their lines of action (a square at the support)
    and the points of interest, in three orthographic views and an isometric one. Returns the
    figure (saved to ``path``)."""
    system = result.system
    fig, axes = subplots(2, 2, figsize=(9.0, 8.5))
    for ax, (title, sx, sy, xl, yl) in zip(axes.flat, VIEWS):
        _draw(ax, result, sx, sy, label=False)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    ax = axes.flat[3]
    right, up = isometric_axes()
    _draw(ax, result, right, up, label=True)
    # the deck's axes as a small triad in the corner
    corner = np.array([0.08, 0.1])
    for k, e in enumerate(np.eye(3)):
        v = np.array([e @ right, e @ up]) * 0.08
        ax.annotate("", xy=corner + v, xytext=corner, xycoords="axes fraction",
                    arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 0.8})
        ax.annotate(f"x{k + 1}", corner + 1.35 * v, xycoords="axes fraction", fontsize=7, color="0.3",
                    ha="center", va="center")
    ax.set_title("isometric", fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    for spine in ax.spines.values():
        spine.set_visible(False)
    j = np.linalg.eigvalsh(system.body.inertia)
    fig.suptitle(f"{system.title or 'Model'}\nm = {system.body.mass:.6g} kg, principal J = "
                 f"{', '.join(f'{x:.4g}' for x in j)} kg m² about G; coordinates from G", fontsize=9)
    fig.tight_layout()
    write_png(fig, path)
    return fig
