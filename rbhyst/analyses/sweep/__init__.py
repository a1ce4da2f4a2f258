"""Sweeps: one base deck run over a suite of motions, intensity levels and deck values.

    from rbhyst.sweep import load_sweep, run_sweep
    sweep = load_sweep("decks/suite.toml")      # every case built and checked (InputError)
    outcome = run_sweep(sweep, workers=2)       # or scheduler="tcp://host:8786"
    header, rows = outcome.table()              # cases.csv

- :mod:`.spec`: the sweep file (pydantic models); :mod:`.motions`: motions listed, found in
  folders, scaled; :mod:`.cases`: the cases and their keys;
- :mod:`.worker`: what a worker process runs; :mod:`.backends`: local processes or Dask;
- :mod:`.store`: the finished cases kept in the output folder; :mod:`.tables`: cases.csv and
  stats.csv; :mod:`.histories`: histories.parquet; :mod:`.runner`: run_sweep.
"""

from rbhyst.analyses.sweep.cases import Case, Sweep, load_sweep
from rbhyst.analyses.sweep.runner import Outcome, SweepIncomplete, run_sweep

__all__ = ["Case", "Outcome", "Sweep", "SweepIncomplete", "load_sweep", "run_sweep"]
