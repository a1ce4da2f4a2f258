"""SRS-matched shocks: make_shocks() for three specifications and both methods.

    python benchmarks/bench_make_shock.py [--repeat 3]

Prints, for each specification (flat 40 g 20-2000 Hz; a knee 10-80 Hz ramp to a 75 g plateau to
2000 Hz; a shipboard-like 5-1000 Hz one) and method, the best wall and CPU time over --repeat
calls of make_shocks() for one axis at the default duration, and the record's samples, the try
and iterations that met the band, and the SRS's range in dB about the specification (or why no
record was made: what the command would stop with).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rbhyst.analyses.shock.specification import Specification  # noqa: E402
from rbhyst.analyses.shock.synthesis import default_duration, make_shocks  # noqa: E402
from rbhyst.errors import AnalysisError  # noqa: E402

G = 9.80665
SPECS = {
    "flat": ([20.0, 2000.0], [40.0, 40.0]),
    "knee": ([10.0, 80.0, 2000.0], [9.44, 75.0, 75.0]),
    "ship": ([5.0, 20.0, 250.0, 1000.0], [2.0, 60.0, 60.0, 40.0]),
}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    for name, (f, a) in SPECS.items():
        spec = Specification(name, np.array(f), np.array(a) * G)
        for method in ("wavelets", "damped-sines"):
            best_wall = best_cpu = float("inf")
            for _ in range(args.repeat):
                w0, c0 = time.perf_counter(), time.process_time()
                try:
                    shock = make_shocks(spec, 10.0, default_duration(spec), method, 1, ["x1"], None)[0]
                except AnalysisError as err:  # what the command would stop with (exit 3)
                    shock = err
                best_wall = min(best_wall, time.perf_counter() - w0)
                best_cpu = min(best_cpu, time.process_time() - c0)
            if isinstance(shock, AnalysisError):
                print(f"{name:5s} {method:12s} wall {best_wall:6.2f} s  cpu {best_cpu:6.2f} s  no record: {shock}")
                continue
            db = shock.ratio_db
            print(f"{name:5s} {method:12s} wall {best_wall:6.2f} s  cpu {best_cpu:6.2f} s  samples {len(shock.acc_g):6d}  "
                  f"try {shock.attempt + 1}  iterations {shock.iterations:2d}  SRS {db.min():+.2f}..{db.max():+.2f} dB")


if __name__ == "__main__":
    main()
