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
    return _run_sweep(sweep, *args, plots=plots, plotter=Plotter() if plots else None, **kwargs)


class Plotter:
    """rbhyst.report.sweep, imported (and matplotlib with it) only when a plot is drawn: a
    finished sweep whose files stand draws none, and half a second of its second went there."""

    from rbhyst.report.sweep_files import PLOT_FILES

    def __getattr__(self, name: str):
        from rbhyst.report import sweep

        return getattr(sweep, name)



