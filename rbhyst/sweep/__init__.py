"""Top layer: ``rbhyst.sweep``, the documented path of :mod:`rbhyst.analyses.sweep`, with the
plots of :mod:`rbhyst.report.sweep`.

    from rbhyst.sweep import load_sweep, run_sweep
"""

from __future__ import annotations

from rbhyst.analyses.sweep import Case, Outcome, Sweep, SweepIncomplete, load_sweep
from rbhyst.analyses.sweep import run_sweep as _run_sweep

__all__ = ["Case", "Outcome", "Sweep", "SweepIncomplete", "load_sweep", "run_sweep"]


def run_sweep(sweep: Sweep, *args, plots: bool = True, **kwargs) -> Outcome:
    """:func:`rbhyst.analyses.sweep.runner.run_sweep` with its plots drawn by rbhyst.report.sweep."""
    plotter = None
    if plots:
        from rbhyst.report import sweep as plotter
    return _run_sweep(sweep, *args, plots=plots, plotter=plotter, **kwargs)



