"""How a run's cost grows: against the number of steps and against the number of elements.

    python benchmarks/bench_scaling.py [--steps 1e4,1e5,1e6,1e7] [--elements 8,32,128,512,1000]

Each case is its own `rbhyst run --no-plots` process on the seed body under a 2 Hz sine at
dt = 1 ms, without the error estimate (analysis.estimate_error = false: its cost is measured in
bench_accuracy.py), timed whole, with its peak memory (ru_maxrss) and its time stepping
(summary.json analysis.wall_s). Elements: as many distinct rows (points along the base, angles
alternating 0/90 deg), so none share a kernel row; their cost per step per element is the
stepping time over compute steps (steps and the monitor's substeps: the more elements, the
stiffer the body) x rows.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import tomli_w

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from conftest import seed_deck  # noqa: E402


def deck(steps: int, n_elements: int | None) -> dict:
    data = seed_deck(duration=steps * 1e-3)
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.3, "frequency_hz": 2.0, "units": "g"},
                                      "x2": {"type": "sine", "amplitude": 0.2, "frequency_hz": 3.0, "units": "g"}}}
    data["analysis"]["estimate_error"] = False
    data["output"] = {"plots": False, "every": max(1, steps // 100_000)}
    if n_elements is not None:
        els = []
        for k in range(n_elements):
            x = -0.12 + 0.59 * k / max(1, n_elements - 1)
            els.append({"point": [x, -0.9429], "angle_deg": 90.0 * (k % 2),
                        "hysteresis": "wri_shear" if k % 2 else "wri_axial"})
        els.append({"vertex": 2, "angle_deg": 0.0, "hysteresis": "wri_axial"})  # against rotation
        data["elements"] = els
    return data


def run(folder: Path, data: dict, name: str) -> dict:
    path = folder / f"{name}.toml"
    path.write_text(tomli_w.dumps(data))
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "rbhyst", "run", str(path), "--out", str(folder / name)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)  # this run's own peak memory, not the children's so far
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"{name}: exit {proc.returncode}: {proc.stderr.read().decode()}")
    s = json.loads((folder / name / "summary.json").read_text())
    return {"wall_s": wall, "stepping_s": s["analysis"]["wall_s"], "rss_MB": usage.ru_maxrss / 1024,
            "taken": s["analysis"]["steps_taken"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", default="1e4,1e5,1e6,1e7")
    ap.add_argument("--elements", default="8,32,128,512,1000")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        print("against steps (seed scene, 8 elements in 3 rows; rows written: at most 100,001)")
        print(f"{'steps':>10} {'wall s':>8} {'stepping s':>11} {'ns/step':>8} {'peak RSS MB':>12}")
        for n in (int(float(x)) for x in args.steps.split(",")):
            r = run(folder, deck(n, None), f"s{n}")
            print(f"{n:>10} {r['wall_s']:>8.2f} {r['stepping_s']:>11.3f} {r['stepping_s'] / n * 1e9:>8.0f} "
                  f"{r['rss_MB']:>12.0f}")
        print("\nagainst elements (10,000 steps; distinct rows)")
        print(f"{'elements':>10} {'wall s':>8} {'stepping s':>11} {'compute steps':>14} {'ns/step/element':>16} "
              f"{'peak RSS MB':>12}")
        for ne in (int(x) for x in args.elements.split(",")):
            r = run(folder, deck(10_000, ne), f"e{ne}")
            # the stiffer the body, the more substeps the monitor asks for: cost per compute step
            print(f"{ne + 1:>10} {r['wall_s']:>8.2f} {r['stepping_s']:>11.3f} {r['taken']:>14} "
                  f"{r['stepping_s'] / r['taken'] / (ne + 1) * 1e9:>16.1f} {r['rss_MB']:>12.0f}")


if __name__ == "__main__":
    main()
