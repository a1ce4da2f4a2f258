"""Shared figure set-up for every PNG rbhyst writes.

Figures are made with matplotlib's object API (no pyplot: no global figure registry) and the
style applies only while a plot function runs (``@styled``), so that a script or notebook
which imports rbhyst keeps its own matplotlib settings.
"""

from __future__ import annotations

import functools

import matplotlib
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter

STYLE = {
    "figure.dpi": 110,
    "savefig.dpi": 130,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "font.size": 9,
    # tick labels of at most about six characters (a power of ten goes above the axis), so that
    # the fixed margins of time_figure hold them
    "axes.formatter.limits": (-3, 4),
    # (not mathtext: parsing every tick label with it was 40 % of a figure; the power of ten
    # reads 1e−3)
    "axes.formatter.use_mathtext": False,
}

#: a panel whose values all stay below this fraction of the largest of its figure is drawn as
#: "at rest" (or, for spectra, named instead of drawn): it is rounding (a symmetric body's cross
#: response, 1e-15 m/s2 under a pulse of 100 m/s2)
NEGLIGIBLE = 1e-9

#: the width of A4 less the report's margins, inches: a figure this wide prints at its own size,
#: its texts at their sizes (9 pt ticks, 8 pt legends: legible); a wider one is shrunk to it
PRINT_WIDTH = 7.3
#: the height a figure may print at (report.html's print style: 235 mm), inches
PRINT_HEIGHT = 235 / 25.4

#: margins of a figure of stacked time series, in inches: left, right, bottom, top, and the gap
#: between axes (room for a power of ten above each)
TIME_MARGINS = (0.8, 0.2, 0.45, 0.35, 0.3)


def styled(plot):
    """Run a plot function under rbhyst's style (every artist it makes and the file it saves)."""

    @functools.wraps(plot)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return plot(*args, **kwargs)

    return wrapper


def subplots(*args, figsize, **kwargs):
    """A new figure and its axes, as pyplot.subplots gives them."""
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)


#: zlib's fastest level for the PNGs: its default (6) spent 20-45 ms a figure compressing, a
#: sixth of the figure's time, for files 10-20 % smaller
PNG_OPTIONS = {"compress_level": 1}


def write_png(fig, path) -> None:
    """The figure as a PNG file."""
    fig.savefig(path, pil_kwargs=dict(PNG_OPTIONS))


def save(fig, path, margins: tuple[float, float, float, float, float] | None = None) -> None:
    """Lay the figure out and write it. ``margins`` (inches, as TIME_MARGINS) places the axes
    directly; without, matplotlib's tight layout measures every label first, which costs a
    draw of its own (about a quarter of the time of a plot of stacked time series)."""
    if margins is None:
        fig.tight_layout()
    else:
        left, right, bottom, top, gap = margins
        w, h = fig.get_size_inches()
        rows = max(1, len(fig.axes))
        height = (h - bottom - top - gap * (rows - 1)) / rows
        fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                            hspace=gap / height)
    write_png(fig, path)


class PlainLogFormatter(LogFormatter):
    """Tick labels of a log axis as plain numbers: 0.01, 0.2, 5, 100 (never 2x10^0 nor 10^-2).

    Which ticks get a label is LogFormatter's choice (every decade; over a decade or two also
    2, 3, 4, 6 or every multiple of it); the text is a decimal from 1e-4 to 1e6 and e-notation
    beyond (1e-5)."""

    def __init__(self):
        super().__init__(labelOnlyBase=False)

    def __call__(self, x, pos=None):
        if not super().__call__(x, pos):
            return ""
        return self.fix_minus(plain_number(x))


def plain_number(x: float) -> str:
    text = f"{x:.6g}"
    if "e" in text:  # 1e-05 -> 1e-5, 2e+06 -> 2e6
        mantissa, exponent = text.split("e")
        text = f"{mantissa}e{int(exponent)}"
    return text


def plain_log_ticks(axis) -> None:
    """Plain labels on a log-scaled axis (ax.xaxis, ax.yaxis), major and minor ticks; call it
    after the axis is made logarithmic (set_xscale resets the formatters)."""
    axis.set_major_formatter(PlainLogFormatter())
    axis.set_minor_formatter(PlainLogFormatter())
