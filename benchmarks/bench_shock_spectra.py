"""Shock response spectra: an 11 ms half-sine and a 1 s shock record, 12 frequencies an octave.

    python benchmarks/bench_shock_spectra.py [--repeat 5]

Prints the first call (numba compiles the kernel, or loads it from its cache), then the best
wall and CPU time over --repeat runs of shock_spectrum() for: a 20 g 11 ms half-sine sampled at
100 kHz (1,101 samples) from 1 Hz to 10 kHz (161 frequencies), primary and residual; and a 1 s
record of decaying random sines at 50 kHz (50,001 samples), 10 Hz to 5 kHz (109 frequencies),
Q = 10 and 50.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rbhyst.solve.shock_spectra import octave_frequencies, shock_spectrum  # noqa: E402

G = 9.80665


def best_of(repeat, fn):
    """(best wall s, best CPU s, last value) of fn() over repeat runs."""
    wall = cpu = np.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        value = fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    dt = 1e-5
    t = np.arange(1101) * dt
    pulse = 20.0 * G * np.where(t <= 0.011, np.sin(np.pi * t / 0.011), 0.0)
    f_pulse = octave_frequencies(1.0, 10_000.0, 12)
    w0 = time.perf_counter()
    shock_spectrum(pulse, dt, f_pulse[:2], [0.05])
    print(f"first call (compile or cache load): {time.perf_counter() - w0:.3f} s")
    wall, cpu, _ = best_of(args.repeat, lambda: shock_spectrum(pulse, dt, f_pulse, [0.05]))
    print(f"half-sine, {len(pulse)} samples, {len(f_pulse)} frequencies, Q 10: {wall:.4f} s wall, {cpu:.4f} s CPU")
    rng = np.random.default_rng(1)
    dt = 2e-5
    t = np.arange(50_001) * dt
    freqs = rng.uniform(10.0, 5000.0, 40)
    record = sum(rng.normal() * np.exp(-5.0 * t) * np.sin(2 * np.pi * f * t) for f in freqs) * G
    f_rec = octave_frequencies(10.0, 5000.0, 12)
    wall, cpu, _ = best_of(args.repeat, lambda: shock_spectrum(record, dt, f_rec, [0.05, 0.01]))
    print(f"record, {len(record)} samples, {len(f_rec)} frequencies, Q 10 and 50: {wall:.4f} s wall, {cpu:.4f} s CPU")


if __name__ == "__main__":
    main()
