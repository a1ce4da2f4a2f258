"""Long runs: wall time and peak memory of `rbhyst run` against the number of steps.

    python benchmarks/bench_long.py [--steps 1e5,1e6,1e7] [--every 1,100]

Each case is a separate `rbhyst run --no-plots` process (the seed's body and isolators under a
2 Hz sine, dt = 1 ms, duration = steps x dt) timed whole, with its peak resident memory from
the kernel (ru_maxrss), and the CSV writing speed in rows per second from the same runs.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import tomli_w

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from conftest import seed_deck  # noqa: E402


def run_case(folder: Path, steps: int, every: int) -> dict:
    data = seed_deck(duration=steps * 1e-3)
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.3, "frequency_hz": 2.0, "units": "g"}}}
    data["output"] = {"every": every, "plots": False}
    deck = folder / f"long_{steps}_{every}.toml"
    deck.write_text(tomli_w.dumps(data))
    out = folder / f"out_{steps}_{every}"
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "rbhyst", "run", str(deck), "--out", str(out)], check=True,
                   capture_output=True)
    wall = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    s = json.loads((out / "summary.json").read_text())
    size = (out / "time_history.csv").stat().st_size
    rows = steps // every + 1
    for p in out.iterdir():
        p.unlink()
    return {"steps": steps, "every": every, "wall_s": wall, "stepping_s": s["analysis"]["wall_s"],
            "peak_rss_MB": max(rss, before) / 1024, "csv_MB": size / 1e6, "rows": rows}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", default="1e5,1e6,1e7")
    ap.add_argument("--every", default="1,100")
    args = ap.parse_args()
    steps = [int(float(x)) for x in args.steps.split(",")]
    everies = [int(x) for x in args.every.split(",")]
    print(f"{'steps':>10} {'every':>6} {'rows':>10} {'wall s':>8} {'stepping s':>10} {'peak RSS MB':>11} "
          f"{'CSV MB':>8} {'rows/s':>10}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in steps:
            for every in everies:
                r = run_case(Path(tmp), n, every)
                # ru_maxrss of children is the largest so far: cases run from small to large
                print(f"{r['steps']:>10} {r['every']:>6} {r['rows']:>10} {r['wall_s']:>8.2f} {r['stepping_s']:>10.2f} "
                      f"{r['peak_rss_MB']:>11.0f} {r['csv_MB']:>8.1f} {r['rows'] / r['wall_s']:>10.0f}")


if __name__ == "__main__":
    main()
