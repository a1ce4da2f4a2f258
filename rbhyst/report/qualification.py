"""trs.png (make-motion) and qualification.png (qualify): the motions' TRS against the RRS with
its tolerance band, and the verdict's demands against their capacities."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter

from ._style import save, styled, subplots

G_STANDARD = 9.80665
AXIS_NAMES = {"x1": "x1 (horizontal)", "x2": "x2 (vertical)"}
#: a deck in space: x1 and x2 horizontal, x3 vertical
SPACE_AXIS_NAMES = {"x1": "x1 (horizontal)", "x2": "x2 (horizontal)", "x3": "x3 (vertical)"}


def _trs_panel(ax, axis: str, rrs, checks: list[tuple[str, object]], names: dict = AXIS_NAMES) -> None:
    """RRS (black), its band over the checked range (shaded), each motion's TRS on the fine grid
    (a line in colour, a dot at each of the standard's points, red rings where outside the band)."""
    lo, hi = rrs.check_range
    f = np.geomspace(lo / 2.0, hi * 2.0, 300)
    ax.plot(f, rrs(f) / G_STANDARD, color="k", lw=1.6, label=f"RRS, ζ = {rrs.damping:g}", zorder=3)
    fb = np.geomspace(lo, hi, 200)
    a, b = rrs.band
    ax.fill_between(fb, a * rrs(fb) / G_STANDARD, b * rrs(fb) / G_STANDARD, color="0.8", alpha=0.6, lw=0,
                    label=f"{a:g}-{b:g} × RRS", zorder=1)
    for label, c in checks:
        # the TRS on the fine grid as the line (its dips between the standard's points shown),
        # the standard's points as dots, red rings where it leaves the band
        f, sa = c.fine_frequency, c.fine_sa / G_STANDARD
        line, = ax.plot(f, sa, lw=1.0, label=label, zorder=4)
        ax.plot(c.frequency_hz, c.trs / G_STANDARD, "o", ms=2.5, color=line.get_color(), zorder=4,
                label="the standard's 1/6-octave points" if label == checks[0][0] else None)
        bad = ~c.fine_within
        if bad.any():
            ax.plot(f[bad], sa[bad], "o", color="red", ms=4, mfc="none", zorder=5)
    ax.axvline(lo, color="0.5", lw=0.6, ls=":")
    ax.axvline(hi, color="0.5", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain = FuncFormatter(lambda v, _: f"{v:g}")
    ax.xaxis.set_major_formatter(plain)
    ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.1e}"[0] in "25" else ""))
    ax.yaxis.set_major_formatter(plain)
    ax.yaxis.set_minor_formatter(plain)  # (a spectrum spans about a decade: every tick labelled)
    ax.tick_params(which="minor", labelsize=7)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("spectral acceleration [g]")
    ax.set_title(f"{names.get(axis, axis)}: {rrs.name}", fontsize=8)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7, loc="lower center")


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
                 notes: tuple[str, ...] = (), space: bool = False) -> None:
    """TRS against RRS per axis (top), and every criterion's demand / capacity as a bar (bottom):
    green within its capacity, red beyond, the capacity at 1. ``space``: the deck is in space
    (x2 horizontal, x3 vertical)."""
    names = SPACE_AXIS_NAMES if space else AXIS_NAMES
    n_axes = max(1, len(rrs))
    n_crit = max(1, len(criteria))
    fig = _figure(n_axes, n_crit)
    grid = fig.add_gridspec(2, n_axes, height_ratios=[4.4, 0.9 + 0.28 * n_crit])
    for k, axis in enumerate(rrs):
        _trs_panel(fig.add_subplot(grid[0, k]), axis, rrs[axis], checks.get(axis, []), names)
    ax = fig.add_subplot(grid[1, :])
    labels = [c["label"] for c in criteria]
    use = np.array([c["demand"] / c["capacity"] for c in criteria]) if criteria else np.zeros(0)
    y = np.arange(len(criteria))[::-1]
    ax.barh(y, use, color=["#2e8b57" if c["pass"] else "#c0392b" for c in criteria], height=0.6)
    for yi, c, u in zip(y, criteria, use):
        ax.annotate(f"{_number(c['demand'])} / {_number(c['capacity'])} {c['unit']}", (u, yi),
                    textcoords="offset points", xytext=(4, -3), fontsize=7)
    ax.axvline(1.0, color="k", lw=1.0)
    ax.set_yticks(y, labels, fontsize=7)
    ax.set_xlim(0.0, max(1.25, float(use.max()) * 1.3 if len(use) else 1.25))
    ax.set_xlabel("demand / capacity")
    if notes:
        ax.set_title("; ".join(notes), fontsize=8)
    ax.grid(True, axis="x", alpha=0.3)
    verdict = "PASS" if passed else "FAIL"
    fig.suptitle(f"Qualification: {verdict}" + (f" — {title}" if title else ""), fontsize=10,
                 color="#2e8b57" if passed else "#c0392b")
    save(fig, path)


def _number(v: float) -> str:
    """4 significant digits, without an exponent for forces in the thousands."""
    return f"{v:.0f}" if 1e3 <= abs(v) < 1e7 else f"{v:.4g}"


def _figure(n_axes: int, n_crit: int):
    from matplotlib.figure import Figure

    return Figure(figsize=(5.4 * n_axes, 4.4 + 1.1 + 0.28 * n_crit))
