"""Labels beside points of a drawing, each placed where it covers no other label and as little
of the drawing as it can: the model's vertices, elements and dampers meet at the same corners.

Labels are placed once the axes have their final size (equal aspect, margins, the figure's
layout), in display pixels; each gets the first of its candidate places, nearest its preferred
direction first, that overlaps no label placed before it and crosses the fewest drawn points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: candidate directions around the anchor (degrees), tried nearest the preferred one first
_DIRECTIONS = np.radians(np.arange(0.0, 360.0, 22.5))
#: distances from the anchor to the label's edge beyond the first, points: close first
_FURTHER = (6.0, 13.0)


@dataclass
class Labels:
    """What is drawn (polylines and points, data units) and the labels to place among it."""

    lines: list[np.ndarray] = field(default_factory=list)
    points: list[tuple[float, float, float]] = field(default_factory=list)
    pending: list[tuple[str, tuple[float, float], tuple[float, float], float, dict]] = field(default_factory=list)

    def line(self, xy) -> None:
        self.lines.append(np.asarray(xy, float).reshape(-1, 2))

    def point(self, x: float, y: float, radius: float = 3.0) -> None:
        """A marker at (x, y) (data units) reaching ``radius`` points around it."""
        self.points.append((float(x), float(y), float(radius)))

    def add(self, text: str, at, prefer, gap: float = 3.0, **kw) -> None:
        """A label ``text`` for the point ``at``, at least ``gap`` points from it, preferably
        towards ``prefer`` (a vector in data units); ``kw`` are Annotation properties."""
        self.pending.append((text, (float(at[0]), float(at[1])), (float(prefer[0]), float(prefer[1])), float(gap),
                             kw))

    def place(self, fig, ax, fixed=()) -> list:
        """Annotate every label on ``ax`` (whose figure is laid out), clear of the texts
        ``fixed`` already there; returns the annotations."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        if not isinstance(fig.canvas, FigureCanvasAgg):
            FigureCanvasAgg(fig)
        renderer = fig.canvas.get_renderer()
        ax.apply_aspect()
        to_px = ax.transData.transform
        pt = renderer.points_to_pixels(1.0)
        obstacles = self._obstacles(to_px, 2.0 * pt, pt)
        frame = ax.get_window_extent(renderer)
        placed = [tuple(t.get_window_extent(renderer).extents) for t in fixed]
        made = []
        for text, at, prefer, first, kw in self.pending:
            note = ax.annotate(text, at, textcoords="offset points", xytext=(0.0, 0.0), ha="center",
                               va="center", **kw)
            box = note.get_window_extent(renderer)
            w, h = box.width, box.height
            anchor = to_px([at])[0]
            best = None
            for gap in (first, *(first + g for g in _FURTHER)):
                for angle in _by_nearness(math.atan2(prefer[1], prefer[0]) if any(prefer) else math.pi / 4):
                    ux, uy = math.cos(angle), math.sin(angle)
                    reach = gap * pt + 0.5 * (abs(ux) * w + abs(uy) * h)
                    cx, cy = anchor[0] + ux * reach, anchor[1] + uy * reach
                    rect = (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2)
                    cost = _cost(rect, obstacles, placed, frame)
                    if best is None or cost < best[0]:
                        best = (cost, rect, (cx - anchor[0]) / pt, (cy - anchor[1]) / pt)
                    if cost == 0:
                        break
                if best[0] == 0:
                    break
            _, rect, ox, oy = best
            note.xyann = (ox, oy)
            placed.append(rect)
            made.append(note)
        return made

    def _obstacles(self, to_px, step: float, pt: float) -> np.ndarray:
        """Points along every drawn line, ``step`` pixels apart, and over every marker."""
        out = []
        if self.points:
            xyr = np.asarray(self.points, float)
            centres = to_px(xyr[:, :2])
            grid = np.linspace(-1.0, 1.0, 5)
            offsets = np.array([(a, b) for a in grid for b in grid])
            for c, r in zip(centres, xyr[:, 2] * pt):
                out.append(c + r * offsets)
        for xy in self.lines:
            px = to_px(xy)
            for a, b in zip(px[:-1], px[1:]):
                n = max(2, int(math.hypot(*(b - a)) / step) + 1)
                out.append(a + (b - a) * np.linspace(0.0, 1.0, n)[:, None])
        return np.vstack(out) if out else np.zeros((0, 2))


def _by_nearness(preferred: float) -> list[float]:
    diff = np.abs((_DIRECTIONS - preferred + math.pi) % (2 * math.pi) - math.pi)
    return [preferred] + [float(a) for a in _DIRECTIONS[np.argsort(diff, kind="stable")]]


def _cost(rect, obstacles: np.ndarray, placed, frame) -> float:
    x0, y0, x1, y1 = rect
    cost = 0.0
    for p in placed:  # another label: never, if any place avoids it
        if x0 < p[2] and p[0] < x1 and y0 < p[3] and p[1] < y1:
            cost += 1000.0
    if x0 < frame.x0 or x1 > frame.x1 or y0 < frame.y0 or y1 > frame.y1:
        cost += 100.0  # outside the axes
    if len(obstacles):
        inside = ((obstacles[:, 0] > x0) & (obstacles[:, 0] < x1) & (obstacles[:, 1] > y0)
                  & (obstacles[:, 1] < y1))
        cost += float(np.count_nonzero(inside))
    return cost
