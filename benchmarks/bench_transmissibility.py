"""Stepped-sine transmissibility on the sample cabinet: one process against a pool.

    python benchmarks/bench_transmissibility.py [--count 40] [--repeat 2]

Runs 0.5-50 Hz (--count log-spaced frequencies) at 0.05, 0.2 and 0.5 g along x1 with one
point of interest, in this process and with 2 workers, and prints the wall time of each
(best of --repeat), the sum of the runs' own times (work done), the machine's load average
before and after (the 2 cores are shared: a pool pays only when the other core is free) and
checks that both give the same numbers to the bit.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import rbhyst  # noqa: E402
from rbhyst.analyses.transmissibility import steady_state, stepped_sine  # noqa: E402

if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    deck = rbhyst.load_deck(ROOT / "decks" / "cabinet_transformer.toml")
    deck = deck.with_values({"output": {"points": [{"name": "top", "point": [0.0, 2.0]}]}})
    freqs = list(np.geomspace(0.5, 50.0, args.count))
    amps = [a * 9.80665 for a in (0.05, 0.2, 0.5)]
    steady_state(deck, "x1", 1.0, 5.0)  # kernels loaded (or compiled) once
    tables = {}
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    for workers in (1, 2):
        best, work = np.inf, 0.0
        for _ in range(args.repeat):
            tic = time.perf_counter()
            res = stepped_sine(deck, "x1", amps, freqs, workers=workers)
            wall = time.perf_counter() - tic
            if wall < best:
                best, work = wall, sum(r.wall_s for r in res.runs)
        tables[workers] = res.table()
        print(f"workers {workers}: {best:.2f} s for {len(res.runs)} steady states (runs' own time {work:.2f} s)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    assert np.array_equal(tables[1], tables[2]), "the pool changed the numbers"
    print("pool and one process: the same numbers")
