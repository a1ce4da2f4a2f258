"""Response spectra: 100 periods x 2 dampings x 3 signals on 40,000 samples, whole and streamed.

    python benchmarks/bench_spectra.py [--repeat 5] [--long]

Prints the first call (numba compiles the kernel, or loads it from its cache), then the
best wall and CPU time over --repeat runs of response_spectrum() at dt = 1, 5 and 10 ms
(the finer the step, the fewer oscillators need substeps: see rbhyst/response/spectra.py),
with points_per_period = 20 (the default) and 0 (maxima over the samples only), and the
same history streamed in chunks of 1,000 samples, checked bit-identical. --long streams
10^7 samples of one signal in chunks of 10^5, never holding the history.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rbhyst.response import SpectrumAccumulator, default_periods, response_spectrum  # noqa: E402
from rbhyst.solve.spectra import substep_counts  # noqa: E402
from rbhyst.model.synthetic import ground_motion  # noqa: E402

N_SAMPLES, DAMPINGS = 40_000, (0.05, 0.02)


def best_of(repeat, fn):
    """(best wall s, best CPU s, last value) of fn() over repeat runs."""
    wall = cpu = np.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        value = fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu, value


def streamed(acc, dt, periods, chunk):
    stream = SpectrumAccumulator(periods, DAMPINGS, acc.shape[1], dt)
    for lo in range(0, len(acc), chunk):
        stream.update(acc[lo:lo + chunk])
    return stream.result()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--long", action="store_true", help="also stream 10^7 samples")
    args = ap.parse_args()
    periods = default_periods()

    start = time.perf_counter()
    response_spectrum(np.zeros((2, 1)), 0.01, periods[:1])
    print(f"first call (compile or load from cache): {time.perf_counter() - start:.2f} s")
    print(f"{len(periods)} periods {periods[0]:g}-{periods[-1]:g} s x {len(DAMPINGS)} dampings x 3 signals, "
          f"{N_SAMPLES} samples; best of {args.repeat}, wall / CPU")

    for dt in (0.001, 0.005, 0.01):
        acc = np.stack([ground_motion(duration=(N_SAMPLES - 1) * dt, dt=dt, seed=s)[1] * 9.80665
                        for s in (1, 2, 3)], axis=1)
        m = substep_counts(periods, dt, 20)
        work = m.sum() / len(periods)
        wall, cpu, whole = best_of(args.repeat, lambda: response_spectrum(acc, dt, periods, DAMPINGS))
        wall0, cpu0, _ = best_of(args.repeat, lambda: response_spectrum(acc, dt, periods, DAMPINGS,
                                                                        points_per_period=0))
        wall_s, cpu_s, part = best_of(args.repeat, lambda: streamed(acc, dt, periods, 1000))
        same = np.array_equal(part.sd, whole.sd) and np.array_equal(part.sa, whole.sa)
        osc_steps = len(DAMPINGS) * 3 * (N_SAMPLES - 1) * m.sum()
        print(f"dt = {dt * 1e3:g} ms: {int((m > 1).sum())} periods with substeps ({work:.2f}x the steps); "
              f"{wall:.3f} / {cpu:.3f} s ({cpu / osc_steps * 1e9:.1f} ns per oscillator step); "
              f"samples only {wall0:.3f} / {cpu0:.3f} s; "
              f"streamed by 1,000 {wall_s:.3f} / {cpu_s:.3f} s, bit-identical: {same}")

    if args.long:
        n, chunk, dt = 10_000_000, 100_000, 0.001
        rng = np.random.default_rng(0)
        stream = SpectrumAccumulator(periods, DAMPINGS, 1, dt)
        w0, c0 = time.perf_counter(), time.process_time()
        for _ in range(n // chunk):
            stream.update(rng.standard_normal((chunk, 1)))
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        print(f"streamed {n:.0e} samples of one signal in chunks of {chunk}: {wall:.1f} / {cpu:.1f} s "
              f"(including the random input)")


if __name__ == "__main__":
    main()
