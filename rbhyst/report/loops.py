"""Force-displacement loops of VRM sets, one panel per set (seed Fig. 2 / Fig. 4 style)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from rbhyst.analyses.calibration import LoopResult
from rbhyst.model.hysteresis import limiting_curve
from rbhyst.report._style import save, styled, subplots

#: at most about this many markers on a measured loop (every point would merge into a band)
DATA_MARKERS = 300


def _display_units(u_max: float, f_max: float) -> tuple[str, float, str, float]:
    """Readable units for data in m and N: mm below 0.1 m, kN from 1 kN."""
    u_unit, u_fac = ("mm", 1e3) if u_max < 0.1 else ("m", 1.0)
    f_unit, f_fac = ("kN", 1e-3) if f_max >= 1e3 else ("N", 1.0)
    return u_unit, u_fac, f_unit, f_fac


@styled
def plot_loops(results: list[LoopResult], path: Path, title: str | None = None,
               initial: dict[str, np.ndarray] | None = None):
    """Model loops (and measured ones when present) with the limiting curves c+ and c-.

    ``initial`` maps set names to a parameter set drawn as a dotted line (the starting
    point of a calibration). Returns the figure (saved to ``path``).
    """
    n = len(results)
    cols = 1 if n == 1 else 2
    rows = math.ceil(n / cols)
    fig, axes = subplots(rows, cols, figsize=(4.6 * cols, 3.9 * rows), squeeze=False)
    for k, (ax, res) in enumerate(zip(axes.flat, results)):
        f_all = res.f if res.f_data is None else np.concatenate([res.f, res.f_data])
        u_unit, u_fac, f_unit, f_fac = _display_units(float(np.max(np.abs(res.u))), float(np.max(np.abs(f_all))))
        ug = np.linspace(res.u.min(), res.u.max(), 400)
        for s, ls in ((1, "--"), (-1, ":")):
            with np.errstate(over="ignore"):
                c = limiting_curve(res.p, s, ug)
            ax.plot(ug * u_fac, c * f_fac, ls, color="0.55", lw=0.9, label=f"c{'+' if s > 0 else '-'}(u)")
        if initial is not None and res.name in initial:
            from rbhyst.model.vrm import loop

            try:
                f0 = loop(initial[res.name], res.u)[0]
                ax.plot(res.u * u_fac, f0 * f_fac, color="C1", lw=0.8, ls="-.", label="initial set")
            except OverflowError:
                pass
        if res.f_data is None:
            ax.plot(res.u * u_fac, res.f * f_fac, color="C0", lw=1.3, label="VRM")
        else:
            # the model as a broad light band under the measurement's open markers (every n-th
            # point): where they agree the markers sit on the band, where they differ both show
            ax.plot(res.u * u_fac, res.f * f_fac, color="C0", lw=2.4, alpha=0.7, zorder=3,
                    label="VRM fit" if initial is not None else "VRM")
            # the measurement a thin line through every point, in the order measured (its loops
            # read as loops, not a cloud), open markers on every n-th
            ax.plot(res.u * u_fac, res.f_data * f_fac, color="0.1", lw=0.6, marker="o", ms=2.8, mfc="none",
                    mew=0.6, markevery=max(1, len(res.u) // DATA_MARKERS), zorder=4, label="test data")
        lo, hi = f_all.min(), f_all.max()
        pad = 0.08 * (hi - lo if hi > lo else 1.0)
        ax.set_ylim((lo - pad) * f_fac, (hi + pad) * f_fac)
        ax.set_xlabel(f"u [{u_unit}]")
        ax.set_ylabel(f"f [{f_unit}]")
        if n > 1:
            ax.set_title(f"({chr(ord('a') + k)}) {res.name}", fontsize=9)
        elif not title:
            ax.set_title(res.name, fontsize=9)
        lines = []
        if res.f_data is not None:
            lines.append(f"NRMSE {res.nrmse:.2%}, R² {res.r2:.4f}")
        closed = [c for c in res.cycles if c.closed]
        if closed:
            lines.append(f"E_D {closed[-1].work:.4g} J/cycle (last closed)")
        if lines:
            ax.text(0.03, 0.97, "\n".join(lines), transform=ax.transAxes, va="top", fontsize=7.5,
                    bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.8", alpha=0.9))
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.axvline(0.0, color="0.6", lw=0.5)
        ax.legend(loc="lower right", fontsize=7, framealpha=0.9)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=10)
    save(fig, path)
    return fig


@styled
def plot_catalogue(name: str, p: np.ndarray, catalogue, path: Path, title: str | None = None):
    """The fitted set's steady cycle at every catalogue amplitude (rbhyst.model.effective) against the
    catalogue: its secant points (+-A, +-k_eff A) as markers, and the ellipse of the equivalent linear
    viscous loop (stiffness k_eff, the same area 2 pi beta_eff k_eff A^2) dashed; a static
    load-deflection row as a square on the set's first loading. Returns the figure."""
    from rbhyst.model.effective import effective
    from rbhyst.model.vrm import loop

    fig, ax = subplots(1, 1, figsize=(8.2, 4.4))
    rows = catalogue.rows
    a_max = max(r.amplitude for r in rows)
    f_max = max([abs(r.k_eff) * r.amplitude for r in catalogue.cycles] + [abs(r.force) for r in catalogue.static])
    u_unit, u_fac, f_unit, f_fac = _display_units(a_max, f_max)
    theta = np.linspace(0.0, 2.0 * np.pi, 200)
    for k, r in enumerate(sorted(catalogue.cycles, key=lambda r: r.amplitude)):
        colour = f"C{k % 10}"
        e = effective(p, r.amplitude)
        ax.plot(e.u * u_fac, e.f * f_fac, color=colour, lw=1.4,
                label=f"{r.amplitude * u_fac:g} {u_unit}: k_eff {e.k_eff:.4g} N/m, beta {e.beta_eff:.3f}")
        ua = r.amplitude * np.cos(theta)
        fa = r.k_eff * ua + 2.0 * r.beta_eff * r.k_eff * r.amplitude * np.sin(theta)
        ax.plot(ua * u_fac, fa * f_fac, color=colour, lw=0.8, ls="--")
        ax.plot(np.array([-1.0, 1.0]) * r.amplitude * u_fac, np.array([-1.0, 1.0]) * r.k_eff * r.amplitude * f_fac,
                ls="none", marker="o", ms=6, mfc="none", mec="0.1", mew=1.0)
    if catalogue.static:
        d = max(r.amplitude for r in catalogue.static)
        ug = np.linspace(0.0, d, 200)
        ax.plot(ug * u_fac, loop(p, ug)[0] * f_fac, color="0.35", lw=1.0, label="first loading")
        ax.plot([r.amplitude * u_fac for r in catalogue.static], [r.force * f_fac for r in catalogue.static],
                ls="none", marker="s", ms=5, mfc="none", mec="0.1", label="catalogue, static")
    ax.plot([], [], ls="none", marker="o", ms=6, mfc="none", mec="0.1", label="catalogue: (±A, ±k_eff A)")
    ax.plot([], [], color="0.3", lw=0.8, ls="--", label="catalogue: equivalent linear loop")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.axvline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel(f"u [{u_unit}]")
    ax.set_ylabel(f"f [{f_unit}]")
    ax.set_title(title or name, fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, framealpha=0.9)
    save(fig, path)
    return fig
