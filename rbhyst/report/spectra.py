"""spectra.png: in-structure response spectra against the ground's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.solve.located import CENTRE, GROUND, LocatedSpectra
from rbhyst.report._style import NEGLIGIBLE, PRINT_WIDTH, plain_log_ticks, plain_number, save, styled, subplots

G_STANDARD = 9.80665
#: one line style per damping ratio, in the deck's order
DAMPING_STYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1)), (0, (1, 3)))


def shown_directions(spectra: LocatedSpectra) -> tuple[list[str], dict[str, float]]:
    """The directions worth a panel, and the largest sa (m/s2) of each one left out."""
    directions = list(dict.fromkeys(d for _, d in spectra.signals))
    largest = {d: max(float(np.max(spectra.sa(loc, d), initial=0.0)) for loc in spectra.locations
                      if (loc, d) in spectra.signals) for d in directions}
    top = max(largest.values(), default=0.0)
    if not top > 0.0:  # nothing moves at all: every panel as it is
        return directions, {}
    dropped = {d: v for d, v in largest.items() if v < NEGLIGIBLE * top}
    return [d for d in directions if d not in dropped], dropped


def phrase_wrap(line: str, width: int) -> str:
    """``line`` in lines of at most about ``width`` characters, broken only between its phrases
    (after ": ", ", ", "; " or before " ("), never inside one: "no response along x1 (sa at most
    3.7e-14 m/s², ..." keeps "sa at most 3.7e-14 m/s²" whole."""
    import re

    pieces = re.split(r"(?<=[:;,]) | (?=\()", line)
    out, current = [], ""
    for piece in pieces:
        if current and len(current) + 1 + len(piece) > width:
            out.append(current)
            current = piece
        else:
            current = f"{current} {piece}" if current else piece
    return "\n".join(out + [current])


@styled
def plot_spectra(spectra: LocatedSpectra, path: Path, title: str = "", shock: bool = False):
    """sa against frequency, log axes, one panel per direction: the ground in black, G and
    the points in colour, one line style per damping (isolation shows as the body's curves
    falling below the ground's above the isolation frequency). A direction with no response
    (below NEGLIGIBLE of the largest) is named in the title instead of drawn; beyond the
    Nyquist frequency of a ground record, where the record has no content, the panel is
    shaded. ``shock``: the maximax of shock response spectra (LocatedShockSpectra.maximax_spectra),
    labelled by Q. Returns the figure (saved to ``path``)."""
    s = spectra.spectrum
    directions, dropped = shown_directions(spectra)
    # one panel a row, as wide as a printed page: its texts print at their sizes
    width = PRINT_WIDTH
    fig, axes = subplots(len(directions), 1, figsize=(width, 0.9 + 3.4 * len(directions)), squeeze=False)
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
                    label += f", Q = {plain_number(1.0 / (2.0 * zeta))}" if shock else f", ζ = {zeta:g}"
                # G a broad light band under the points' lines: a point near G (or moving as G does)
                # would hide it otherwise
                ax.plot(f[order], sa[order, j], color=colours[loc], ls=DAMPING_STYLES[j % len(DAMPING_STYLES)],
                        lw={GROUND: 1.6, CENTRE: 3.2}.get(loc, 1.1), alpha=0.45 if loc == CENTRE else 1.0,
                        zorder={GROUND: 3, CENTRE: 1.5}.get(loc, 2), label=label,
                        solid_capstyle="butt")
        ax.set_xscale("log")
        ax.set_yscale("log")
        nyquist = spectra.nyquist_hz(direction)
        if nyquist is not None and nyquist < f.max():
            ax.axvspan(nyquist, f.max() * 10.0, color="0.5", alpha=0.12, lw=0, zorder=0,
                       label=f"beyond the record's Nyquist frequency, {plain_number(nyquist)} Hz")
            ax.axvline(nyquist, color="0.4", lw=0.9, ls="--", zorder=1)
            ax.set_xlim(f.min() / 1.2, f.max() * 1.2)
        plain_log_ticks(ax.xaxis)
        plain_log_ticks(ax.yaxis)
        ax.set_xlabel("oscillator frequency [Hz]")
        ax.set_ylabel(f"{'maximax' if shock else 'sa'} [m/s²]")
        ax.set_title(f"along {direction}")
        ax.grid(True, which="both", alpha=0.25)
        g_axis = ax.secondary_yaxis("right", functions=(lambda a: a / G_STANDARD, lambda a: a * G_STANDARD))
        g_axis.set_ylabel(f"{'maximax' if shock else 'sa'} [g]")
        plain_log_ticks(g_axis.yaxis)
        ax.legend(fontsize=8, loc="best")
    if shock:
        heading = "Shock response spectra (maximax absolute acceleration)" + (f": {title}" if title else "")
        lines = [heading, "Q = " + ", ".join(plain_number(1.0 / (2.0 * z)) for z in s.dampings)
                 + "; positive, negative, primary and residual in srs.csv"]
    else:
        heading = "Response spectra (maximax absolute acceleration)" + (f": {title}" if title else "")
        lines = [heading, "damping " + ", ".join(f"{z:g}" for z in s.dampings)]
    lines += [f"no response along {d} (sa at most {v:.2g} m/s², below {plain_number(NEGLIGIBLE)} of the largest: "
              "rounding)" for d, v in dropped.items()]
    fig.suptitle("\n".join(phrase_wrap(line, int(13 * width)) for line in lines), fontsize=9)
    save(fig, path)
    return fig
