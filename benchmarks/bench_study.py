"""The reference solution's cost and accuracy, and a whole study, on a deck.

    python benchmarks/bench_study.py [--deck decks/seed_wri.toml] [--repeat 5]

Prints the reference's wall time (time stepping only, best of --repeat) at rtol 1e-10,
1e-12 and 1e-14 with its steps and reversals, how far each is from the tightest, and
the end-to-end time of `rbhyst study --no-plots` (numba caches warm).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rbhyst.model.deck import load_deck  # noqa: E402
from rbhyst.solve.integrators import reference  # noqa: E402
from rbhyst.model.system import assemble  # noqa: E402
from rbhyst.solve.plan import settings_from_deck  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", default=str(ROOT / "decks" / "seed_wri.toml"))
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    deck_path = Path(args.deck)
    deck = load_deck(deck_path)
    settings = settings_from_deck(deck)
    system = assemble(deck, deck_path.parent)

    results = {}
    for rtol in (1e-10, 1e-12, 1e-14):
        best = np.inf
        for _ in range(args.repeat):
            start = time.perf_counter()
            res, stats = reference.solve_with_stats(system, settings, rtol=rtol)
            total = time.perf_counter() - start
            best = min(best, stats["wall_s"])
        results[rtol] = (res, stats, best, total)
    tight = results[1e-14][0]
    print(f"scene: {deck_path.name}, {tight.time[-1]:g} s, {system.n_output_elements} elements")
    print(" rtol    wall_s  total_s  steps  rejected  reversals  max rel. diff to rtol 1e-14 (u1, u2, theta3)")
    for rtol, (res, st, best, total) in results.items():
        diff = np.max(np.abs(res.d - tight.d), axis=0) / np.max(np.abs(tight.d), axis=0)
        print(f"{rtol:5.0e}  {best:7.3f}  {total:7.3f}  {st['steps']:6d}  {st['rejected_steps']:8d}  "
              f"{st['reversals']:9d}  " + "  ".join(f"{x:.1e}" for x in diff))

    rbhyst = shutil.which("rbhyst") or f"{sys.executable} -m rbhyst"
    with tempfile.TemporaryDirectory() as tmp:
        cmd = rbhyst.split() + ["study", str(deck_path), "--no-plots", "--out", str(Path(tmp) / "s")]
        subprocess.run(cmd, check=True, capture_output=True)  # warm the caches
        start = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        print(f"rbhyst study --no-plots end to end: {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
