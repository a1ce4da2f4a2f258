"""Time rbhyst sweep: cases of the seed deck (40 s at dt = 1 ms) on local workers and on a
local Dask cluster.

    python benchmarks/bench_sweep.py [--cases 200,2000] [--workers 2] [--no-dask]

Each case varies body.mass a little (so every case is computed, none reused). Reported per
run: the whole wall time; the start-up (until the first batch comes back: processes started,
kernels loaded); the wall time per case after start-up, (end - first batch) / the cases after
it; the median computing of a case (analysis.wall_s + accuracy.wall_s: its time stepping and its
error estimate); and their ratio. A case
costs its worker more than its time stepping: building the scene, and the run's own
reductions of every step (rows, extremes, plot data); one case in one process is timed
first.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"


def sweep_file(folder: Path, n: int) -> Path:
    masses = ", ".join(repr(800.0 + 0.01 * k) for k in range(n))
    path = folder / f"bench_{n}.toml"
    path.write_text(f'deck = "{DECK.as_posix()}"\n\n[vary]\n"body.mass" = [{masses}]\n')
    return path


def one_case_breakdown() -> None:
    import rbhyst

    deck = rbhyst.load_deck(DECK)
    rbhyst.run(deck)  # kernels loaded, records read
    t = []
    for _ in range(7):
        tic = time.perf_counter()
        r = rbhyst.run(deck)
        t.append((time.perf_counter() - tic, r.wall_s + r.accuracy["wall_s"]))
    print(f"one case in one process: rbhyst.run {min(x for x, _ in t) * 1e3:.1f} ms, "
          f"of which computing (analysis.wall_s + accuracy.wall_s) {min(w for _, w in t) * 1e3:.1f} ms")


def bench(n: int, folder: Path, workers: int | None = None, scheduler: str | None = None) -> dict:
    from rbhyst.analyses.sweep import load_sweep, run_sweep

    sw = load_sweep(sweep_file(folder, n))
    out = folder / f"out_{n}_{'dask' if scheduler else 'local'}"
    tic = time.perf_counter()
    o = run_sweep(sw, out=out, workers=workers, scheduler=scheduler, fresh=True, plots=False)
    total = time.perf_counter() - tic
    after = (o.t_end - o.t_first) / max(1, o.computed - o.n_first)
    wall = statistics.median(o.wall_s)
    return {"cases": n, "where": o.where, "total_s": total, "startup_s": o.t_first - o.t_start,
            "per_case_ms": after * 1e3, "analysis_ms": wall * 1e3, "ratio": after / wall,
            "worker_ms": statistics.median(o.elapsed_s) * 1e3}


def show(r: dict) -> None:
    print(f"{r['cases']:>5} cases on {r['where']}: {r['total_s']:.2f} s in all, start-up {r['startup_s']:.2f} s; "
          f"after it {r['per_case_ms']:.1f} ms wall per case = {r['ratio']:.2f} x its computing "
          f"({r['analysis_ms']:.1f} ms); a case in its worker {r['worker_ms']:.1f} ms")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="200,2000")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-dask", action="store_true")
    args = ap.parse_args()
    sizes = [int(x) for x in args.cases.split(",")]
    one_case_breakdown()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for n in sizes:
            show(bench(n, folder, workers=args.workers))
        if args.no_dask:
            return
        from distributed import LocalCluster

        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster:  # this machine only
            for n in sizes:
                show(bench(n, folder, scheduler=cluster.scheduler_address))


if __name__ == "__main__":
    main()
