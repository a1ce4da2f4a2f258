"""What the error estimate costs against the run's own time stepping, and how honest it is.

    python benchmarks/bench_estimate.py [--random 16] [--repeat 5] [--cases FOLDER ...]

For the seed deck, the median over N random scenes (tests/test_accuracy.py's generator, seeds
1000...) and every deck of the folders given: ``accuracy.wall_s / analysis.wall_s`` (each the
best of ``--repeat`` runs in one process, kernels loaded), of the estimate the seconds of its
compiled calls (``loops ms``: the companion's and its probe's loops, and where the check has no
core of its own the source and the reductions too, one call; nan where the adaptive solutions
gave the estimate; side by side on two cores they can sum to more than the estimate took), the
estimate's status, and the
largest estimated error over the largest true error (the run's rows against the reference at
rtol 1e-12, every column the estimate covers: what the tests hold within [0.5, 10]). The
process keeps freed memory as the command's does (rbhyst.allocator), so that a run's arrays are
not fresh pages each time. On a machine shared with other work the ratios scatter: repeat.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def true_error(res) -> float:
    from rbhyst.solve.estimate import column_errors
    from rbhyst.solve.history import estimate_columns
    from rbhyst.solve.integrators import reference

    exact = reference.integrate(res.system, res.time, rtol=1e-12)
    cols = estimate_columns(res.layout)
    index = [c for _, c, _ in cols]
    ref = res.layout.table(exact.raw(res.system))[:, index]
    return float(np.max(column_errors(res.table[:, index], ref, [k for k, _, _ in cols], [f for _, _, f in cols],
                                      res.system)))


def measure(path, repeat: int, integrator: str | None = None):
    import rbhyst

    kw = {"integrator": integrator} if integrator else {}
    best_step, best_est, best_loops, res = np.inf, np.inf, np.inf, None
    for _ in range(repeat):
        res = rbhyst.run(path, **kw)
        best_step = min(best_step, res.wall_s)
        best_est = min(best_est, res.accuracy["wall_s"])
        # the companion's compiled calls (their seconds): the rest is Python
        best_loops = min(best_loops, res.accuracy.get("companion", {}).get("wall_s", np.nan))
    est = max(v for k, v in res.accuracy["estimated_error"].items() if not k.startswith("sa_"))
    true = true_error(res)
    return best_est / best_step, best_step, best_est, res.accuracy["status"], est, true, best_loops


def line(name, m) -> str:
    ratio, step, est_wall, status, est, true, loops = m
    honesty = est / true if true > 0 else float("inf")
    return (f"  {name:<34} {step * 1e3:9.2f} {est_wall * 1e3:9.2f} {loops * 1e3:9.2f} {ratio:7.1f}x  {status:<12} "
            f"{est:9.2e} {true:9.2e} {honesty:7.2f}")


def main() -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    import rbhyst
    from rbhyst.allocator import keep_freed_memory

    keep_freed_memory()
    from conftest import write_deck
    from test_accuracy import random_scene

    from rbhyst.solve.integrators import names

    ap = argparse.ArgumentParser()
    ap.add_argument("--random", type=int, default=16, help="random scenes (default 16)")
    ap.add_argument("--repeat", type=int, default=5, help="runs per scene, the best counted (default 5)")
    ap.add_argument("--cases", action="append", default=[], help="a folder of decks to add (any number)")
    args = ap.parse_args()

    rbhyst.run(ROOT / "decks" / "seed_wri.toml")  # kernels loaded
    head = (f"  {'scene':<34} {'step ms':>9} {'est ms':>9} {'loops ms':>9} {'est/step':>8}  {'status':<12} "
            f"{'estimate':>9} {'true':>9} {'est/true':>7}")
    print("seed deck (decks/seed_wri.toml)\n" + head)
    print(line("seed_wri", measure(ROOT / "decks" / "seed_wri.toml", args.repeat)))

    tmp = Path(tempfile.mkdtemp())
    print(f"\nrandom scenes (tests/test_accuracy.py, seeds 1000..{999 + args.random})\n" + head)
    ratios, honesty = [], []
    for seed in range(args.random):
        folder = tmp / f"r{seed}"
        folder.mkdir()
        path = write_deck(folder, random_scene(np.random.default_rng(1000 + seed)))
        try:
            m = measure(path, args.repeat)
        except rbhyst.AnalysisError as err:
            print(f"  random {seed:<27} refused: {err}")
            continue
        ratios.append(m[0])
        honesty.append(m[4] / m[5] if m[5] > 0 else np.inf)
        print(line(f"random {seed}", m))
    if ratios:
        print(f"  median est/step {np.median(ratios):.1f}x; est/true from {min(honesty):.2f} to {max(honesty):.2f}")

    for folder in args.cases:
        print(f"\n{folder}\n" + head)
        for path in sorted(Path(folder).glob("*.toml")):
            title = rbhyst.load_deck(path).title or ""
            named = re.search(r"\((\S+)\)", title)  # a deck that names its integrator in its title
            integrator = named.group(1) if named and named.group(1) in names() else None
            try:
                print(line(path.name, measure(path, max(1, args.repeat // 2), integrator)))
            except rbhyst.AnalysisError as err:
                print(f"  {path.name:<34} refused: {err}")


if __name__ == "__main__":
    main()
