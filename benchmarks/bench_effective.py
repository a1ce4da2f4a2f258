"""Effective properties and catalogue fits: the cost of one steady cycle and of a fit.

    python benchmarks/bench_effective.py [--repeat 5]

Prints the wall time (best of --repeat) of rbhyst.model.effective.effective for the WRI-like set
(kb 2e4 N/m, f0 800 N, alpha 200 /m) at amplitudes from 0.01 to 100 mm (its settling cycles grow
as 1 / (alpha A): the cycle is run until it repeats itself), then of fit_catalogue on a three-row
catalogue of that set with kb, f0, alpha free, and on one of seed Table 3's shear set mirrored
with beta1, beta2 free as well.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rbhyst.analyses.catalogue import Catalogue, Row, fit_catalogue, symmetric  # noqa: E402
from rbhyst.model.effective import effective  # noqa: E402


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def catalogue(p, amplitudes):
    rows = []
    for i, a in enumerate(amplitudes, start=2):
        e = effective(p, a)
        rows.append(Row(i, a, e.k_eff, e.beta_eff, None))
    return Catalogue("bench", tuple(rows))


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    wri = symmetric(np.array([2e4, 800.0, 200.0, 0, 0, 0, 0, 0]))
    effective(wri, 0.01)  # (the kernel loaded or compiled once)
    for a in (1e-5, 1e-4, 1e-3, 1e-2, 1e-1):
        wall, e = best(lambda: effective(wri, a), args.repeat)
        print(f"effective at {a * 1e3:g} mm: {e.settling_cycles} settling cycles, {wall * 1e3:.3f} ms")
    start = symmetric(np.array([5e4, 300.0, 50.0, 0, 0, 0, 0, 0]))
    wall, fit = best(lambda: fit_catalogue(start, catalogue(wri, [0.002, 0.008, 0.02])), args.repeat)
    print(f"fit kb, f0, alpha to 3 rows: {wall:.3f} s, largest misfit {fit.worst:.2e}, {fit.nfev} evaluations")
    shear = symmetric(np.array([220000.0, 1150.0, 680.0, 100.0, 300.0, 0, 0, 0]))
    start = symmetric(np.array([1e5, 800.0, 300.0, 50.0, 100.0, 0, 0, 0]))
    free = ("kb", "f0", "alpha", "beta1", "beta2")
    wall, fit = best(lambda: fit_catalogue(start, catalogue(shear, [0.002, 0.005, 0.01]), free), max(1, args.repeat // 2))
    print(f"fit kb, f0, alpha, beta1, beta2 to 3 rows: {wall:.3f} s, largest misfit {fit.worst:.2e}, {fit.nfev} evaluations")
