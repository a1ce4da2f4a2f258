"""srs.png and pvss.png: a shock response spectrum as a shock engineer reads it.

srs.png: absolute acceleration (g) against natural frequency (Hz), log-log, maximax with the
positive and negative, primary and residual spectra. pvss.png: the pseudo-velocity shock
spectrum on tripartite (four-coordinate) axes: pseudo-velocity against frequency, with lines of
constant relative displacement (PV = 2 pi f D, rising) and of constant pseudo-acceleration
(PV = A / (2 pi f), falling), and the 50 and 100 in/s severity lines (1.27 and 2.54 m/s) of
Gaberson's and Morse's work on the stress a pseudo-velocity can cause.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from rbhyst.report._style import plain_log_ticks, plain_number, save, styled, subplots
from rbhyst.solve.shock_spectra import ShockSpectrum

G_STANDARD = 9.80665
#: the severity lines of the PVSS, m/s: 50 and 100 in/s
SEVERITY_M_S = ((1.27, "50 in/s (1.27 m/s)"), (2.54, "100 in/s (2.54 m/s)"))
#: how each of the spectra is drawn: attribute, label, line style
CURVES = (("maximax", "maximax", "-"), ("positive", "positive", "--"), ("negative", "negative", ":"),
          ("primary", "primary (during the record)", "-."), ("residual", "residual (after it)", (0, (5, 1, 1, 1))))


@styled

def _srs_axes(ax) -> None:
    """An SRS's axes: log-log, natural frequency against peak absolute acceleration in g."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_ticks(ax.xaxis)
    plain_log_ticks(ax.yaxis)
    ax.grid(True, which="both", alpha=0.25)
    ax.set_xlabel("natural frequency [Hz]")
    ax.set_ylabel("peak absolute acceleration [g]")
    ax.legend(fontsize=7, loc="best")

def plot_srs(srs: ShockSpectrum, path: Path, title: str = ""):
    """The SRS of every Q, g against Hz on log axes (returns the figure, saved to ``path``)."""
    fig, ax = subplots(figsize=(6.8, 4.8))
    f = srs.frequencies_hz
    for j, q in enumerate(srs.qs):
        colour = f"C{j}"
        for name, label, style in CURVES:
            values = getattr(srs, name)[:, j] / G_STANDARD
            shown = np.where(values > 0.0, values, np.nan)  # a zero has no place on a log axis
            ax.plot(f, shown, color=colour, ls=style, lw=1.6 if name == "maximax" else 1.0,
                    label=f"{label}, Q = {plain_number(q)}" if len(srs.qs) > 1 else label)
    _srs_axes(ax)
    q = ", ".join(plain_number(v) for v in srs.qs)
    ax.set_title(f"Shock response spectrum{': ' + title if title else ''}\nQ = {q}", fontsize=9)
    save(fig, path)
    return fig


@styled
def plot_pvss(srs: ShockSpectrum, path: Path, title: str = ""):
    """The pseudo-velocity of every Q on tripartite axes (returns the figure, saved to ``path``)."""
    fig, ax = subplots(figsize=(6.8, 5.6))
    f = srs.frequencies_hz
    pv = srs.pv
    for j, q in enumerate(srs.qs):
        shown = np.where(pv[:, j] > 0.0, pv[:, j], np.nan)
        ax.plot(f, shown, color=f"C{j}", lw=1.6, label=f"PVSS, Q = {plain_number(q)}", zorder=4)
    top = float(np.nanmax(np.where(pv > 0.0, pv, np.nan))) if np.any(pv > 0.0) else 1.0
    _tripartite_axes(ax, f, min(top / 1e3, 0.5 * SEVERITY_M_S[0][0] / 10.0), max(3.0 * top, 2.0 * SEVERITY_M_S[1][0]))
    ax.set_ylabel("pseudo-velocity 2πf·max|x| [m/s]")
    ax.legend(fontsize=7, loc="lower center")
    ax.set_title(f"Pseudo-velocity shock spectrum{': ' + title if title else ''}\n"
                 "rising lines: constant displacement; falling: constant acceleration", fontsize=9)
    save(fig, path)
    return fig


@styled
def plot_located_pvss(spectra, path: Path, title: str = ""):
    """A run's pseudo-velocity shock spectra (LocatedShockSpectra) on tripartite axes, one panel a
    direction: the ground in black, G and the points in colour, the first Q (every Q is in
    srs.csv). Returns the figure (saved to ``path``)."""
    from rbhyst.report._style import PRINT_WIDTH
    from rbhyst.solve.located import CENTRE, GROUND

    directions = list(dict.fromkeys(d for _, d in spectra.signals))
    fig, axes = subplots(len(directions), 1, figsize=(PRINT_WIDTH, 0.9 + 3.6 * len(directions)), squeeze=False)
    others = [loc for loc in spectra.locations if loc != GROUND]
    colours = {loc: f"C{i}" for i, loc in enumerate(others)} | {GROUND: "k"}
    first = spectra.spectra[0]
    f = first.frequencies_hz
    for ax, direction in zip(axes.flat, directions):
        # each panel its own range: a direction that hardly moves is read on its own scale
        pvs = [s.pv[:, 0] for (_, d), s in zip(spectra.signals, spectra.spectra) if d == direction]
        top = max(float(np.max(v)) for v in pvs)
        least = min((float(np.min(v[v > 0.0])) for v in pvs if np.any(v > 0.0)), default=top)
        top = top if top > 0.0 else 1.0
        lo_v = min(max(top / 1e4, 0.7 * least), 0.5 * SEVERITY_M_S[0][0] / 10.0)
        hi_v = max(3.0 * top, 2.0 * SEVERITY_M_S[1][0])
        for loc in spectra.locations:
            if (loc, direction) not in spectra.signals:
                continue
            pv = spectra.of(loc, direction).pv[:, 0]
            label = "ground" if loc == GROUND else "G (mass centre)" if loc == CENTRE else loc
            ax.plot(f, np.where(pv > 0.0, pv, np.nan), color=colours[loc], lw={GROUND: 1.6, CENTRE: 2.4}.get(loc, 1.1),
                    alpha=0.6 if loc == CENTRE else 1.0, label=label, zorder=4)
        _tripartite_axes(ax, f, lo_v, hi_v)
        ax.set_ylabel("pseudo-velocity [m/s]")
        ax.set_title(f"along {direction}", fontsize=9)
        ax.legend(fontsize=7, loc="lower center")
    fig.suptitle(f"Pseudo-velocity shock spectra{': ' + title if title else ''}, Q = {plain_number(first.qs[0])}\n"
                 "rising lines: constant displacement; falling: constant acceleration", fontsize=9)
    save(fig, path)
    return fig


def _tripartite_axes(ax, f: np.ndarray, lo_v: float, hi_v: float) -> None:
    """Log axes over the frequencies ``f`` (to 1.5 times beyond either end) and
    pseudo-velocities lo_v..hi_v (m/s), with the tripartite grid and the severity lines."""
    lo_f, hi_f = f.min() / 1.5, f.max() * 1.5
    ax.set_xlim(lo_f, hi_f)
    ax.set_ylim(lo_v, hi_v)
    ax.set_xscale("log")
    ax.set_yscale("log")
    _tripartite_grid(ax, lo_f, hi_f, lo_v, hi_v)
    for v, label in SEVERITY_M_S:
        ax.axhline(v, color="0.25", lw=1.0, ls="--", zorder=3)
        # a third of the way across: the grid's own labels stand at the edges
        ax.text(lo_f * (hi_f / lo_f) ** 0.33, v * 1.04, label, fontsize=7, color="0.25", va="bottom",
                bbox={"fc": "white", "ec": "none", "pad": 0.5, "alpha": 0.8}, zorder=5)
    plain_log_ticks(ax.xaxis)
    plain_log_ticks(ax.yaxis)
    ax.grid(False)
    ax.set_xlabel("natural frequency [Hz]")


def _tripartite_grid(ax, lo_f: float, hi_f: float, lo_v: float, hi_v: float) -> None:
    """Lines of constant displacement D (m) and pseudo-acceleration A (g) at every decade across
    the axes, each labelled where it leaves them."""
    f = np.geomspace(lo_f, hi_f, 50)
    w = 2.0 * np.pi * f
    # D = PV / w ranges over lo_v / w_max .. hi_v / w_min; A = PV w likewise
    for kind, lo, hi in (("D", lo_v / w[-1], hi_v / w[0]), ("A", lo_v * w[0] / G_STANDARD, hi_v * w[-1] / G_STANDARD)):
        for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1):
            value = 10.0 ** e
            pv = w * value if kind == "D" else value * G_STANDARD / w
            ax.plot(f, pv, color="0.6" if kind == "D" else "0.75", lw=0.6, zorder=1)
            inside = np.flatnonzero((pv >= lo_v) & (pv <= hi_v))
            if inside.size:
                k = inside[-1] if kind == "D" else inside[0]
                text = f"{plain_number(value)} m" if kind == "D" else f"{plain_number(value)} g"
                ax.text(f[k], pv[k], text, fontsize=6, color="0.45", rotation=0,
                        ha="right" if kind == "D" else "left", va="top" if kind == "D" else "bottom", zorder=2)


@styled
def plot_pulse(pulse, path: Path, title: str = ""):
    """A classical pulse as played (rbhyst.model.shock_pulses.ClassicalPulse): its acceleration
    with the nominal main pulse and the standard's band, and the table's velocity and
    displacement (returns the figure, saved to ``path``)."""
    from rbhyst.model.shock_pulses import PULSE_TOLERANCE, table_motion

    s = pulse.series
    t = s.times
    a = np.asarray(s.values, float)
    v, x = table_motion(a, s.dt)
    peak = abs(pulse.amplitude)
    fig, axes = subplots(3, 1, figsize=(6.8, 7.0), sharex=True)
    ms = 1e3 * t
    ax = axes[0]
    inside = (t >= pulse.main_start) & (t <= pulse.main_end)
    band, outside = PULSE_TOLERANCE["band"] * peak / G_STANDARD, PULSE_TOLERANCE["outside"] * peak / G_STANDARD
    nominal = pulse.nominal(t) / G_STANDARD
    ax.fill_between(ms, np.where(inside, nominal - band, -outside), np.where(inside, nominal + band, outside),
                    color="C2", alpha=0.18, lw=0, label=f"tolerance band (±{PULSE_TOLERANCE['band']:g} A)")
    ax.plot(ms, nominal, color="0.3", lw=1.0, ls="--", label="nominal pulse")
    ax.plot(ms, a / G_STANDARD, color="C0", lw=1.3, label="as played")
    ax.set_ylabel("acceleration [g]")
    ax.legend(fontsize=7, loc="best")
    axes[1].plot(ms, v, color="C1", lw=1.2)
    axes[1].set_ylabel("table velocity [m/s]")
    axes[2].plot(ms, 1e3 * x, color="C3", lw=1.2)
    axes[2].set_ylabel("table displacement [mm]")
    axes[2].set_xlabel("time [ms]")
    for ax in axes:
        ax.axhline(0.0, color="0.5", lw=0.6)
    end = f"ends at {v[-1]:.2g} m/s, {1e3 * x[-1]:.2g} mm"
    heading = textwrap.fill(title, 90) + "\n" if title else ""
    axes[0].set_title(f"{heading}{pulse.kind}, {peak / G_STANDARD:.4g} g, {1e3 * pulse.duration:.4g} ms; the table "
                      f"{end}", fontsize=9)
    save(fig, path)
    return fig


@styled
def plot_srs_check(shocks, path: Path, band_db: tuple[float, float], title: str = ""):
    """Each record's SRS against the specification and its tolerance band, g against Hz on log
    axes (``shocks``: rbhyst.analyses.shock.synthesis.Shock; returns the figure, saved to ``path``)."""
    fig, ax = subplots(figsize=(6.8, 4.8))
    lo, hi = (10.0 ** (b / 20.0) for b in band_db)
    f, spec = shocks[0].frequency_hz, shocks[0].spec / G_STANDARD
    ax.fill_between(f, lo * spec, hi * spec, color="0.85", label=f"tolerance {band_db[0]:g}/+{band_db[1]:g} dB")
    ax.plot(f, spec, color="k", lw=1.2, label="specification")
    for j, s in enumerate(shocks):
        ax.plot(f, s.srs / G_STANDARD, color=f"C{j}", lw=1.4, label=f"{s.axis}: maximax SRS")
        out = ~s.within
        if out.any():
            ax.plot(f[out], s.srs[out] / G_STANDARD, "x", color="red", label=f"{s.axis}: outside the band")
    _srs_axes(ax)
    ax.set_title(f"SRS check{': ' + title if title else ''}", fontsize=9)
    save(fig, path)
    return fig


@styled
def plot_shock_records(shocks, path: Path, title: str = ""):
    """Each record's acceleration (g), and the table's velocity (m/s) and displacement (mm) from rest,
    against time: where it starts and that it ends at rest (``shocks``:
    rbhyst.analyses.shock.synthesis.Shock; returns the figure, saved to ``path``)."""
    from rbhyst.model.baseline import integrate

    fig, axes = subplots(3, 1, figsize=(6.8, 6.4), sharex=True)
    for j, s in enumerate(shocks):
        t = s.dt * np.arange(len(s.acc_g))
        v, d = integrate(s.acc_g * G_STANDARD, s.dt)
        # a table's stroke is read in millimetres, not as 0.004 under a "1e-3"
        for ax, values in zip(axes, (s.acc_g, v, d * 1e3)):
            ax.plot(t, values, color=f"C{j}", lw=0.8, label=s.axis)
    for ax, label in zip(axes, ("acceleration [g]", "velocity [m/s]", "displacement [mm]")):
        ax.set_ylabel(label)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.grid(True, alpha=0.25)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time [s]")
    axes[0].set_title(f"The records{': ' + title if title else ''}", fontsize=9)
    save(fig, path)
    return fig
