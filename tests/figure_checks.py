"""What a figure's defects look like once it is drawn, measured on matplotlib's own layout:
titles that overlap, texts too small to read once printed on A4, a legend over the data, tick
labels of an axis."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Text

#: A4 less the report's margins (inches): a wider figure is shrunk to it in print, a taller one
#: than A4_HEIGHT to that; a narrower one is printed at its pixels' CSS size (96 a CSS inch),
#: up to A4_WIDTH
A4_WIDTH, A4_HEIGHT = 7.3, 235 / 25.4


def drawn(fig):
    """The figure laid out and drawn (its texts' places are known after a draw); drawn again
    only where something changed since."""
    if not isinstance(fig.canvas, FigureCanvasAgg) or fig.stale:
        FigureCanvasAgg(fig).draw()
    return fig


def titles(fig) -> list[Text]:
    """The figure's suptitle and every axes' titles, where they say something."""
    out = [fig._suptitle] if fig._suptitle is not None else []
    for ax in fig.axes:
        out += [ax.title, ax._left_title, ax._right_title]
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def overlapping_titles(fig) -> list[tuple[str, str]]:
    """Pairs of titles whose boxes overlap once drawn."""
    r = drawn(fig).canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(r)) for t in titles(fig)]
    return [(a, b) for i, (a, p) in enumerate(boxes) for b, q in boxes[i + 1:] if p.overlaps(q)]


def print_scale(fig) -> float:
    """What printing report.html on A4 multiplies the figure's sizes by (its CSS: max-width 100 %,
    max-height 235 mm, otherwise the PNG's pixels at 96 a CSS inch)."""
    import matplotlib

    from rbhyst.report._style import STYLE

    w, h = fig.get_size_inches()
    dpi = STYLE.get("savefig.dpi", matplotlib.rcParams["savefig.dpi"])
    natural = dpi / 96.0
    return min(natural, A4_WIDTH / w, A4_HEIGHT / h)


def smallest_print_pt(fig) -> float:
    """The smallest text of the figure in points once report.html is printed on A4."""
    shrink = print_scale(fig)
    sizes = [t.get_fontsize() for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
    return min(sizes) * shrink


def points_under_legend(ax) -> int:
    """How many of the axes' data points (of its visible lines) the legend's box covers."""
    legend = ax.get_legend()
    if legend is None:
        return 0
    r = drawn(ax.figure).canvas.get_renderer()
    box = legend.get_window_extent(r)
    count = 0
    for line in ax.lines:
        if not line.get_visible() or line.get_alpha() == 0.0 or len(line.get_xdata()) == 0:
            continue
        xy = ax.transData.transform(np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float))
        inside = (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
        count += int(inside.sum())
    return count


def tick_values(axis) -> list[float]:
    """The values of an axis' labelled ticks (major and minor) within its view."""
    drawn(axis.axes.figure)
    lo, hi = sorted(axis.get_view_interval())
    out = []
    for ticks in (axis.get_major_ticks(), axis.get_minor_ticks()):
        for t in ticks:
            if t.label1.get_visible() and t.label1.get_text().strip() and lo <= t.get_loc() <= hi:
                out.append(float(t.get_loc()))
    return sorted(out)
