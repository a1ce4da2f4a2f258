"""Runs through the Python API in one process, against their own time stepping.

    python benchmarks/bench_api.py [--runs 30] [--deck decks/seed_wri.toml]

Loads the deck once, then runs it --runs times with the record scaled by 0.5-1.5 (a new deck
each time, by Deck.with_values), in memory, and prints the wall time per run against the
computing it contains: the time stepping (`analysis.wall_s`) and the error estimate
(`accuracy.wall_s`); then the same with `--no-estimate` (analysis.estimate_error = false),
and on 2 processes (runs per second).
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def batch(deck_path: str, scales, estimate: bool = True) -> tuple[float, float, float, int]:
    """Wall time of the runs, their time stepping and their error estimates, and their count."""
    import rbhyst

    deck = rbhyst.load_deck(deck_path).with_values({"analysis.estimate_error": estimate})
    rbhyst.run(deck.with_values({"analysis.duration": 1.0}))  # kernels loaded
    t0 = time.perf_counter()
    stepping = estimating = 0.0
    for s in scales:
        res = rbhyst.run(deck.with_values({"excitation.support.x1.scale": float(s)}))
        stepping += res.wall_s
        estimating += res.accuracy["wall_s"] if estimate else 0.0
    return time.perf_counter() - t0, stepping, estimating, len(scales)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--deck", default=str(ROOT / "decks" / "seed_wri.toml"))
    args = ap.parse_args()
    scales = np.linspace(0.5, 1.5, args.runs)
    for estimate in (True, False):
        wall, stepping, estimating, n = batch(args.deck, scales, estimate)
        computing = stepping + estimating
        print(f"1 process, estimate {'on ' if estimate else 'off'}: {n} runs in {wall:.3f} s = "
              f"{wall / n * 1e3:.1f} ms a run; time stepping {stepping / n * 1e3:.1f} ms, estimate "
              f"{estimating / n * 1e3:.1f} ms a run; wall / computing {wall / computing:.2f}; "
              f"overhead {(wall - computing) / n * 1e3:.1f} ms a run; {n / wall:.1f} runs/s")
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(batch, [args.deck] * 2, [scales[:2]] * 2))  # start the workers, load the kernels
        t0 = time.perf_counter()
        parts = list(pool.map(batch, [args.deck] * 2, [scales[0::2], scales[1::2]]))
        total = time.perf_counter() - t0
    print(f"2 processes: {n} runs in {total:.3f} s = {n / total:.1f} runs/s "
          f"(per process: {', '.join(f'{w:.2f} s' for w, *_ in parts)})")


if __name__ == "__main__":
    main()
