"""spectra.png: in-structure response spectra against the ground's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.solve.located import CENTRE, GROUND, LocatedSpectra
from rbhyst.report._style import save, styled, subplots

G_STANDARD = 9.80665
#: one line style per damping ratio, in the deck's order
DAMPING_STYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))


@styled
def plot_spectra(spectra: LocatedSpectra, path: Path, title: str = "") -> None:
    """sa against frequency, log axes, one panel per direction: the ground in black, G and
    the points in colour, one line style per damping (isolation shows as the body's curves
    falling below the ground's above the isolation frequency)."""
    s = spectra.spectrum
    directions = list(dict.fromkeys(d for _, d in spectra.signals))
    fig, axes = subplots(1, len(directions), figsize=(5.2 * len(directions), 4.4), squeeze=False)
    colours = {loc: "k" if loc == GROUND else f"C{i}" for i, loc in
               enumerate(loc for loc in spectra.locations if loc != GROUND)}
    colours[GROUND] = "k"
    f = 1.0 / s.periods
    order = np.argsort(f)
    for ax, direction in zip(axes.flat, directions):
        for loc in spectra.locations:
            if (loc, direction) not in spectra.signals:
                continue
            sa = spectra.sa(loc, direction)
            for j, zeta in enumerate(s.dampings):
                label = ("ground" if loc == GROUND else "G (mass centre)" if loc == CENTRE else loc)
                if len(s.dampings) > 1:
                    label += f", ζ = {zeta:g}"
                ax.plot(f[order], sa[order, j], color=colours[loc], ls=DAMPING_STYLES[j % len(DAMPING_STYLES)],
                        lw=1.6 if loc == GROUND else 1.1, zorder=3 if loc == GROUND else 2, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("oscillator frequency [Hz]")
        ax.set_ylabel("sa [m/s²]")
        ax.set_title(f"along {direction}")
        ax.grid(True, which="both", alpha=0.25)
        g_axis = ax.secondary_yaxis("right", functions=(lambda a: a / G_STANDARD, lambda a: a * G_STANDARD))
        g_axis.set_ylabel("sa [g]")
        ax.legend(fontsize=7, loc="best")
    damping = ", ".join(f"{z:g}" for z in s.dampings)
    heading = "Response spectra (maximax absolute acceleration)" + (f": {title}" if title else "")
    fig.suptitle(f"{heading}\ndamping {damping}", fontsize=9)
    save(fig, path)
