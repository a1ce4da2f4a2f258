"""Work-precision diagrams of ``rbhyst study``: error against run time and against dt."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.ticker import NullFormatter

from rbhyst.analyses.study import Run, Study
from rbhyst.report._style import save, styled, subplots

MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def _ok(runs: list[Run]) -> list[Run]:
    return sorted((r for r in runs if r.failed is None and math.isfinite(r.err_max) and r.err_max > 0),
                  key=lambda r: r.dt)


def _label(name: str, study: Study) -> str:
    order = study.orders.get(name, {}).get("order")
    return f"{name} (order {order:.2f})" if order is not None else name


def _dt_label(dt: float) -> str:
    return f"{dt * 1e3:.4g} ms"


def _reference_note(study: Study) -> str:
    ref = study.reference
    return f"reference: DOP853, rtol {ref['rtol']:g}, {ref['reversals']} reversals, {ref['wall_s']:.3g} s"


@styled
def plot_error_vs_runtime(study: Study, path: Path) -> None:
    """Log-log err_max against wall time, one line per integrator, each point labelled with its dt."""
    fig, ax = subplots(figsize=(7.5, 5.2))
    for k, (name, runs) in enumerate(study.by_integrator().items()):
        ok = _ok(runs)
        if not ok:
            continue
        x = [r.wall_s for r in ok]
        y = [r.err_max for r in ok]
        ax.loglog(x, y, marker=MARKERS[k % len(MARKERS)], ms=5, lw=1.2, color=f"C{k}", label=_label(name, study))
        for r in ok:
            ax.annotate(_dt_label(r.dt), (r.wall_s, r.err_max), textcoords="offset points", xytext=(4, 3),
                        fontsize=6.5, color=f"C{k}")
        for r in ok:
            if r.substeps:
                ax.plot(r.wall_s, r.err_max, marker="o", ms=10, mfc="none", mec="0.5", lw=0)
    ax.axvline(study.reference["wall_s"], color="0.4", ls=":", lw=1.0)
    ax.annotate("reference", (study.reference["wall_s"], 0.02), xycoords=("data", "axes fraction"),
                rotation=90, fontsize=7, color="0.3", xytext=(3, 0), textcoords="offset points")
    ax.set_xlabel("wall time of the time stepping [s]")
    ax.set_ylabel(f"error: max over {_names(study)} of max|q − q_ref| / max|q_ref|")
    ax.set_title(f"Error against run time{': ' + study.title if study.title else ''}\n"
                 f"{study.duration:g} s of motion; {_reference_note(study)}", fontsize=8.5)
    _substep_legend(ax, study)
    ax.legend(fontsize=7.5, loc="lower left")
    save(fig, path)


@styled
def plot_error_vs_dt(study: Study, path: Path) -> None:
    """Log-log err_max against dt, one line per integrator, with a slope-2 guide."""
    fig, ax = subplots(figsize=(7.5, 5.2))
    lo, hi = math.inf, 0.0
    for k, (name, runs) in enumerate(study.by_integrator().items()):
        ok = _ok(runs)
        if not ok:
            continue
        x = [r.dt for r in ok]
        y = [r.err_max for r in ok]
        lo, hi = min(lo, min(y)), max(hi, max(y))
        ax.loglog(x, y, marker=MARKERS[k % len(MARKERS)], ms=5, lw=1.2, color=f"C{k}", label=_label(name, study))
        est = [r.est_max for r in ok]
        ax.loglog(x, est, marker=MARKERS[k % len(MARKERS)], ms=9, mfc="none", lw=0, color=f"C{k}", alpha=0.7)
        for r in ok:
            if r.substeps:
                ax.plot(r.dt, r.err_max, marker="o", ms=10, mfc="none", mec="0.5", lw=0)
        for r in runs:
            if r.failed is not None:
                ax.axvline(r.dt, color=f"C{k}", ls="--", lw=0.6, alpha=0.5)
    if hi > 0:
        dts = np.array(sorted(study.dts))
        guide = lo * (dts / dts[0]) ** 2
        keep = guide <= max(hi, lo * 4)  # within the data's range
        ax.loglog(dts[keep], guide[keep], color="0.6", ls="--", lw=0.9, label="slope 2")
    ax.axvline(study.deck_dt, color="0.4", ls=":", lw=1.0)
    ax.annotate("deck dt", (study.deck_dt, 0.98), xycoords=("data", "axes fraction"), rotation=90,
                fontsize=7, color="0.3", xytext=(3, 0), textcoords="offset points", va="top")
    ax.set_xticks(sorted(study.dts))
    ax.set_xticklabels([_dt_label(dt) for dt in sorted(study.dts)])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("dt")
    ax.set_ylabel(f"error: max over {_names(study)} of max|q − q_ref| / max|q_ref|")
    ax.set_title(f"Error against time step{': ' + study.title if study.title else ''}\n"
                 f"order: slope over the asymptotic range; {_reference_note(study)}", fontsize=8.5)
    ax.plot([], [], marker="s", ms=9, mfc="none", color="0.4", lw=0, label="each run's own error estimate")
    _substep_legend(ax, study)
    ax.legend(fontsize=7.5, loc="upper left")
    save(fig, path)


def _names(study: Study) -> str:
    """The coordinates measured, as the axis label says them: u1, u2, θ3 (the 6 coordinates in space)."""
    greek = [c.replace("theta", "θ") for c in study.coordinates]
    return ", ".join(greek) if len(greek) <= 3 else f"the {len(greek)} coordinates"


def _substep_legend(ax, study: Study) -> None:
    if any(r.substeps for r in study.runs):
        ax.plot([], [], marker="o", ms=10, mfc="none", mec="0.5", lw=0,
                label="stiffness substeps taken (off the dt ladder)")
    if any(r.failed for r in study.runs):
        ax.plot([], [], color="0.5", ls="--", lw=0.6, label="a run failed at this dt (see study.json)")


def write_plots(study: Study, out: Path) -> list[str]:
    plot_error_vs_runtime(study, out / "error_vs_runtime.png")
    plot_error_vs_dt(study, out / "error_vs_dt.png")
    return ["error_vs_runtime.png", "error_vs_dt.png"]
