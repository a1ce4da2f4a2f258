"""transmissibility.png: T against frequency, one panel per location, one curve per amplitude."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.report._style import plain_log_ticks, styled, subplots, write_png

G_STANDARD = 9.80665
#: a cross response below this is not drawn (a symmetric body's is rounding: 1e-17)
SHOWN_ABOVE = 1e-6


@styled
def plot_transmissibility(result, path: Path, title: str = ""):
    """log-log T with plain tick labels; along the excitation solid, across it dashed (in space
    the second direction across dash-dotted); T = 1
    marked. Returns the figure (saved to ``path``)."""
    table = result.table()
    locations = list(dict.fromkeys(c[2:-3] for c in result.columns))
    amplitudes = list(dict.fromkeys(table[:, 1]))
    cols = min(len(locations), 2)
    rows = -(-len(locations) // cols)
    fig, axes = subplots(rows, cols, figsize=(5.4 * cols, 4.2 * rows), squeeze=False)
    # the other directions of the body (x2 or x1 in the plane; two of x1, x2, x3 in space)
    across = [d for d in dict.fromkeys(c[-2:] for c in result.columns) if d != result.direction]
    styles = [(result.direction, "-"), *zip(across, ("--", "-."))]
    for ax, loc in zip(axes.flat, locations):
        for i, amp in enumerate(amplitudes):
            mine = table[table[:, 1] == amp]
            f = mine[:, 0]
            for direction, style in styles:
                t = mine[:, 2 + result.columns.index(f"T_{loc}_{direction}")].copy()
                t[t < SHOWN_ABOVE] = np.nan
                if np.isnan(t).all():
                    continue
                label = (f"{amp:.4g} m/s² ({amp / G_STANDARD:.3g} g), "
                         f"{'along' if direction == result.direction else 'across'} ({direction})")
                ax.plot(f, t, style, color=f"C{i}", marker="o" if len(f) < 30 else None, ms=3, lw=1.2,
                        label=label)
        ax.axhline(1.0, color="0.3", lw=0.9, ls=":", zorder=1)
        ax.annotate("T = 1", (1.0, 1.0), xycoords=("axes fraction", "data"), ha="right", va="bottom",
                    fontsize=7, color="0.3")
        ax.set_xscale("log")
        ax.set_yscale("log")
        plain_log_ticks(ax.xaxis)
        plain_log_ticks(ax.yaxis)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("T = peak |at| / amplitude")
        ax.set_title("G (mass centre)" if loc == "G" else f"point {loc}")
        ax.grid(True, which="both", alpha=0.25)
    for ax in axes.flat[len(locations):]:
        ax.set_visible(False)
    # one legend for every panel (their curves are the same amplitudes and directions), under
    # them: inside a panel it covered the low frequencies' curves
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(2, len(labels)), fontsize=8)
    heading = f"Transmissibility, stepped sine along {result.direction}" + (f"\n{title}" if title else "")
    fig.suptitle(heading, fontsize=9)
    fig.set_layout_engine("constrained")
    write_png(fig, path)
    return fig
