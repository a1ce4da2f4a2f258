"""trs.png (make-motion) and qualification.png (qualify): the motions' TRS against the RRS with
its tolerance band, and the verdict's demands against their capacities."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter

from ._style import PRINT_HEIGHT, PRINT_WIDTH, save, styled, subplots, write_png

G_STANDARD = 9.80665
AXIS_NAMES = {"x1": "x1 (horizontal)", "x2": "x2 (vertical)"}
#: a deck in space: x1 and x2 horizontal, x3 vertical
SPACE_AXIS_NAMES = {"x1": "x1 (horizontal)", "x2": "x2 (horizontal)", "x3": "x3 (vertical)"}


#: the narrowest a text may print on A4 (points): figures are drawn at most PRINT_WIDTH wide, their
#: texts at least this large, so that print does not shrink them below it
PRINT_PT = 8.0
#: a log axis spanning at most about a decade is labelled at these multiples of its powers of ten
#: (the plateaus of the standards, 1.25 g and 1.92 g, read between 1.2 and 1.5, 1.5 and 2)
FINE_SUBS = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0)


def log_ticks(axis, lo: float, hi: float) -> None:
    """Labelled ticks on a log axis from ``lo`` to ``hi``: at FINE_SUBS over about a decade, at
    1, 2 and 5 over two or three, every decade beyond; each label a plain number (0.5, 1.25)."""
    from matplotlib.ticker import FixedLocator, NullFormatter

    decades = np.log10(hi / lo)
    subs = FINE_SUBS if decades <= 1.3 else (1.0, 2.0, 5.0) if decades <= 3.0 else (1.0,)
    ticks = [m * 10.0 ** k for k in range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
             for m in subs if lo <= m * 10.0 ** k <= hi]
    axis.set_major_locator(FixedLocator(ticks))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def _trs_panel(ax, axis: str, rrs, checks: list[tuple[str, object]], names: dict = AXIS_NAMES,
               pt: float = PRINT_PT) -> None:
    """RRS (black, its plateau's value written on it), its band over the checked range (shaded),
    each motion's TRS on the fine grid (a line in colour, a dot at each of the standard's points,
    red rings where outside the band)."""
    lo, hi = rrs.check_range
    f = np.geomspace(lo / 2.0, hi * 2.0, 300)
    curve = rrs(f) / G_STANDARD
    ax.plot(f, curve, color="k", lw=1.6, label=f"RRS, ζ = {rrs.damping:g}", zorder=3)
    fb = np.geomspace(lo, hi, 200)
    a, b = rrs.band
    ax.fill_between(fb, a * rrs(fb) / G_STANDARD, b * rrs(fb) / G_STANDARD, color="0.8", alpha=0.6, lw=0,
                    label=f"{a:g}-{b:g} × RRS", zorder=1)
    values = [curve, b * rrs(fb) / G_STANDARD]
    for label, c in checks:
        # the TRS on the fine grid as the line (its dips between the standard's points shown),
        # the standard's points as dots, red rings where it leaves the band
        ff, sa = c.fine_frequency, c.fine_sa / G_STANDARD
        line, = ax.plot(ff, sa, lw=1.0, label=label, zorder=4)
        ax.plot(c.frequency_hz, c.trs / G_STANDARD, "o", ms=2.5, color=line.get_color(), zorder=4,
                label="the standard's 1/6-octave points" if label == checks[0][0] else None)
        values.append(sa)
        bad = ~c.fine_within
        if bad.any():
            ax.plot(ff[bad], sa[bad], "o", color="red", ms=4, mfc="none", zorder=5)
    top = int(np.argmax(curve))  # the plateau's start: its value said where it is
    ax.annotate(f"{curve[top]:.3g} g", (f[top], curve[top]), textcoords="offset points", xytext=(-4, -10),
                ha="right", fontsize=pt)
    ax.axvline(lo, color="0.5", lw=0.6, ls=":")
    ax.axvline(hi, color="0.5", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    # the legend goes in a strip below every curve, sized for its rows: it covers none of them
    entries = 2 + len(checks)
    ncol = 1 if entries <= 4 else 2
    share = min(0.6, (0.25 + 0.19 * -(-entries // ncol)) / 2.7)  # of the panel's height (about 2.7 in)
    low = min(float(np.min(v)) for v in values) / 1.1
    high = max(float(np.max(v)) for v in values) * 1.15
    bottom = low / (high / low) ** (share / (1.0 - share))
    ax.set_ylim(bottom, high)
    log_ticks(ax.yaxis, bottom, high)
    plain = FuncFormatter(lambda v, _: f"{v:g}")
    ax.xaxis.set_major_formatter(plain)
    ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.1e}"[0] in "25" else ""))
    ax.tick_params(which="both", labelsize=pt)
    ax.set_xlabel("frequency [Hz]", fontsize=max(9.0, pt))
    ax.set_ylabel("spectral acceleration [g]", fontsize=max(9.0, pt))
    ax.set_title(f"{names.get(axis, axis)}\n{rrs.name}", fontsize=pt)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=pt, loc="lower center", ncol=ncol)


@styled
def plot_trs(motions, rrs: dict, path: Path, title: str = "") -> None:
    """One panel per axis: the RRS, its band and every motion's TRS."""
    axes_names = list(rrs)
    names = SPACE_AXIS_NAMES if "x3" in rrs else AXIS_NAMES
    fig, axes = subplots(1, len(axes_names), figsize=(5.4 * len(axes_names), 4.4), squeeze=False)
    for ax, axis in zip(axes.flat, axes_names):
        _trs_panel(ax, axis, rrs[axis], [(f"TRS, motion {m.number}", m.records[axis].check) for m in motions
                                         if axis in m.records], names)
    fig.suptitle("Test response spectra (TRS) against the required (RRS)" + (f": {title}" if title else ""),
                 fontsize=9)
    save(fig, path)


@styled
def plot_verdict(checks: dict, rrs: dict, criteria: list[dict], passed: bool, path: Path, title: str = "",
                 notes: tuple[str, ...] = (), space: bool = False):
    """TRS against RRS per axis (top, two a row), and every criterion's demand / capacity as a
    bar (bottom): green within its capacity, red beyond, the capacity at 1. ``space``: the deck
    is in space (x2 horizontal, x3 vertical). PRINT_WIDTH wide, every text at least PRINT_PT:
    legible on an A4 page as it is. Returns the figure (saved to ``path``)."""
    from matplotlib.figure import Figure

    names = SPACE_AXIS_NAMES if space else AXIS_NAMES
    cols = min(2, max(1, len(rrs)))
    rows = -(-max(1, len(rrs)) // cols)
    n_crit = max(1, len(criteria))
    bars = 0.9 + 0.22 * n_crit
    height = 0.6 + 3.4 * rows + bars
    # taller than a page, print shrinks it: its texts are drawn larger by as much
    pt = PRINT_PT / min(1.0, PRINT_HEIGHT / height)
    fig = Figure(figsize=(PRINT_WIDTH, height), layout="constrained")
    grid = fig.add_gridspec(rows + 1, cols, height_ratios=[3.4] * rows + [bars])
    for k, axis in enumerate(rrs):
        _trs_panel(fig.add_subplot(grid[k // cols, k % cols]), axis, rrs[axis], checks.get(axis, []), names, pt)
    ax = fig.add_subplot(grid[rows, :])
    labels = [c["label"] for c in criteria]
    use = np.array([c["demand"] / c["capacity"] for c in criteria]) if criteria else np.zeros(0)
    y = np.arange(len(criteria))[::-1]
    ax.barh(y, use, color=["#2e8b57" if c["pass"] else "#c0392b" for c in criteria], height=0.6)
    for yi, c, u in zip(y, criteria, use):
        ax.annotate(f"{_number(c['demand'])} / {_number(c['capacity'])} {c['unit']}", (u, yi),
                    textcoords="offset points", xytext=(4, -3), fontsize=pt)
    ax.axvline(1.0, color="k", lw=1.0)
    ax.set_yticks(y, labels)
    ax.tick_params(labelsize=pt)
    ax.set_xlim(0.0, max(1.25, float(use.max()) * 1.3 if len(use) else 1.25))
    ax.set_xlabel("demand / capacity", fontsize=max(9.0, pt))
    if notes:
        ax.set_title("; ".join(notes), fontsize=pt, wrap=True)
    ax.grid(True, axis="x", alpha=0.3)
    verdict = "PASS" if passed else "FAIL"
    fig.suptitle(f"Qualification: {verdict}" + (f" — {title}" if title else ""), fontsize=max(10.0, pt + 1.0), wrap=True,
                 color="#2e8b57" if passed else "#c0392b")
    write_png(fig, path)
    return fig


def _number(v: float) -> str:
    """4 significant digits, without an exponent for forces in the thousands."""
    return f"{v:.0f}" if 1e3 <= abs(v) < 1e7 else f"{v:.4g}"
