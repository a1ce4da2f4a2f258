"""Time rbhyst sweep: cases of the seed deck on local workers (and on a local Dask cluster),
against the cases' own computing.

    python benchmarks/bench_sweep.py [--cases 200,2000,10000] [--workers 2] [--duration 8]
                                     [--records DIR] [--plots] [--no-dask]

Each case varies body.mass a little (so every case is computed, none reused). The motion is
El Centro (I-ELC270 along x1, I-ELC180 along x2, from --records, by default the folder the
tests use: ../shared/records beside the project) where it is there, else the deck's own
synthetic records; ``--duration`` cuts the run (``analysis.duration``; default: the deck's,
40 s). Each sweep runs in a process of its own, so that its peak memory is its own.

Reported per sweep: reading the sweep file and building its cases (``load_sweep``); the
sweep's wall time (``run_sweep``), its start-up (until the first batch comes back) and the
wall time per case after it; the sum of the cases' computing (each case's analysis.wall_s +
accuracy.wall_s, from the store) and the bound 1.2 x that / workers + 5 s; what a case costs
its worker around its computing (building the scene from the deck, the run's reductions:
elapsed_s - wall_s); what the sweep's own process spends (its CPU time, of it the journal
appends, the tables at the end and the plots); and the peak resident memory of the sweep's
process and of each local worker (VmHWM, /proc; a Dask cluster's workers are not its
children and are not measured).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"
RECORDS = ROOT.parent / "shared" / "records"


def sweep_file(folder: Path, n: int, duration: float | None, records: Path | None) -> Path:
    masses = ", ".join(repr(800.0 + 0.01 * k) for k in range(n))
    text = f'deck = "{DECK.as_posix()}"\n\n'
    if records is not None:
        text += ('[[motions]]\nname = "elc"\n'
                 f'x1 = {{ file = "{(records / "I-ELC270.AT2").as_posix()}", units = "g" }}\n'
                 f'x2 = {{ file = "{(records / "I-ELC180.AT2").as_posix()}", units = "g" }}\n\n')
    text += "[vary]\n"
    if duration is not None:
        text += f'"analysis.duration" = [{float(duration)!r}]\n'
    text += f'"body.mass" = [{masses}]\n'
    path = folder / f"bench_{n}.toml"
    path.write_text(text)
    return path


def one_case_breakdown(duration: float | None, records: Path | None) -> None:
    import rbhyst

    deck = rbhyst.load_deck(DECK)
    values = {}
    if duration is not None:
        values["analysis.duration"] = float(duration)
    if records is not None:
        values["excitation.support"] = {"x1": {"file": str(records / "I-ELC270.AT2"), "units": "g"},
                                        "x2": {"file": str(records / "I-ELC180.AT2"), "units": "g"}}
    deck = deck.with_values(values)
    rbhyst.run(deck)  # kernels loaded, records read
    t = []
    for _ in range(7):
        tic = time.perf_counter()
        r = rbhyst.run(deck)
        t.append((time.perf_counter() - tic, r.wall_s, r.accuracy["wall_s"]))
    print(f"one case in one process: rbhyst.run {min(x for x, _, _ in t) * 1e3:.1f} ms, of which time stepping "
          f"(analysis.wall_s) {min(w for _, w, _ in t) * 1e3:.1f} ms and error estimate (accuracy.wall_s) "
          f"{min(a for _, _, a in t) * 1e3:.1f} ms", flush=True)


# ---------------------------------------------------------------- memory, from /proc


def _status(pid: int | str) -> dict[str, int]:
    out = {}
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith(("VmRSS:", "VmHWM:")):
                    k, v = line.split(":")
                    out[k] = int(v.split()[0]) * 1024
    except OSError:
        pass
    return out


def _children(pid: int) -> list[int]:
    out = []
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as fh:
                out.extend(int(x) for x in fh.read().split())
    except OSError:
        pass
    return out


class Memory:
    """Samples the resident memory of this process and its children (the workers) twice a
    second: each one's peak (VmHWM) and this process's resident size over time."""

    def __init__(self, every: float = 0.5):
        self.every, self.peaks, self.parent_rss = every, {}, []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        me = os.getpid()
        while not self._stop.wait(self.every):
            self.parent_rss.append(_status(me).get("VmRSS", 0))
            for pid in _children(me):
                hwm = _status(pid).get("VmHWM")
                if hwm:
                    self.peaks[pid] = max(self.peaks.get(pid, 0), hwm)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


# ---------------------------------------------------------------- one sweep, in its own process


class Timer:
    """Wall time spent in a function, added up."""

    def __init__(self):
        self.s, self.calls = 0.0, 0

    def wrap(self, fn):
        def timed(*a, **kw):
            tic = time.perf_counter()
            try:
                return fn(*a, **kw)
            finally:
                self.s += time.perf_counter() - tic
                self.calls += 1
        return timed


def run_one(n: int, workers: int, duration: float | None, records: Path | None, plots: bool,
            scheduler: str | None) -> dict:
    from rbhyst.analyses.sweep import runner
    from rbhyst.analyses.sweep.store import Journal
    from rbhyst.report import sweep as plotter
    from rbhyst.sweep import load_sweep, run_sweep

    journal, tables, drawing = Timer(), Timer(), Timer()
    Journal.add = journal.wrap(Journal.add)
    runner._write_files = tables.wrap(runner._write_files)
    plotter.write_plots = drawing.wrap(plotter.write_plots)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = sweep_file(folder, n, duration, records)
        with Memory() as mem:
            tic = time.perf_counter()
            sw = load_sweep(path)
            loaded = time.perf_counter()
            cpu0 = time.process_time()
            o = run_sweep(sw, out=folder / "out", workers=None if scheduler else workers, scheduler=scheduler,
                          fresh=True, plots=plots)
            cpu = time.process_time() - cpu0
            end = time.perf_counter()
        lines = (folder / "out" / ".rbhyst-sweep" / "journal.jsonl").read_text().splitlines()[1:]
        entries = [json.loads(x) for x in lines]
    wall = [e["wall_s"] for e in entries if "wall_s" in e]
    elapsed = [e["elapsed_s"] for e in entries if "elapsed_s" in e]
    hwm = _status(os.getpid()).get("VmHWM", 0)
    computing = sum(wall)
    return {"cases": n, "where": o.where, "load_s": loaded - tic, "sweep_s": end - loaded,
            "startup_s": o.t_first - o.t_start, "end_s": end - loaded - (o.t_end - o.t_start),
            "per_case_ms": (o.t_end - o.t_first) / max(1, o.computed - o.n_first) * 1e3,
            "computing_s": computing, "bound_s": 1.2 * computing / workers + 5.0,
            "case_ms": statistics.median(wall) * 1e3,
            "around_ms": statistics.median(e - w for e, w in zip(elapsed, wall)) * 1e3,
            "around_sum_s": sum(elapsed) - computing,
            "parent_cpu_s": cpu, "journal_s": journal.s, "journal_calls": journal.calls,
            "tables_s": tables.s - drawing.s, "plots_s": drawing.s,
            "parent_peak_mb": hwm / 2**20, "parent_rss_mb": [x / 2**20 for x in mem.parent_rss],
            "worker_peak_mb": sorted(v / 2**20 for v in mem.peaks.values())}


def show(r: dict, workers: int) -> None:
    ratio = r["sweep_s"] / (r["computing_s"] / workers)
    rss = r["parent_rss_mb"]
    print(f"{r['cases']:>6} cases on {r['where']}: load_sweep {r['load_s']:.2f} s; run_sweep {r['sweep_s']:.1f} s "
          f"(start-up {r['startup_s']:.2f} s, then {r['per_case_ms']:.2f} ms per case, after the last case "
          f"{r['end_s']:.2f} s: tables {r['tables_s']:.2f} s, plots {r['plots_s']:.2f} s)\n"
          f"       computing {r['computing_s']:.1f} s in all (median {r['case_ms']:.1f} ms a case): "
          f"run_sweep = {ratio:.3f} x computing / {workers}; bound 1.2 x + 5 s = {r['bound_s']:.1f} s: "
          f"{'met' if r['sweep_s'] <= r['bound_s'] else 'NOT met'} (with load_sweep: "
          f"{'met' if r['sweep_s'] + r['load_s'] <= r['bound_s'] else 'not met'})\n"
          f"       around the computing in the worker: {r['around_ms']:.2f} ms a case ({r['around_sum_s']:.1f} s "
          f"in all); the sweep's process: {r['parent_cpu_s']:.1f} s CPU, of it journal appends "
          f"{r['journal_s']:.2f} s in {r['journal_calls']} calls\n"
          f"       peak memory: the sweep's process {r['parent_peak_mb']:.0f} MB (resident {rss[0] if rss else 0:.0f} MB "
          f"at the start, {max(rss or [0]):.0f} MB at most), workers "
          f"{', '.join(f'{m:.0f}' for m in r['worker_peak_mb'])} MB", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="200,2000")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--duration", type=float, default=None, help="analysis.duration [s] (default: the deck's)")
    ap.add_argument("--records", type=Path, default=RECORDS, help="the folder of I-ELC270.AT2 and I-ELC180.AT2")
    ap.add_argument("--plots", action="store_true", help="draw the plots too (as the command does)")
    ap.add_argument("--no-dask", action="store_true", help="local workers only (not also a local Dask cluster)")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)  # one sweep, in this process: JSON out
    ap.add_argument("--scheduler", help=argparse.SUPPRESS)
    args = ap.parse_args()
    records = args.records if (args.records / "I-ELC180.AT2").is_file() else None
    if args.one:
        r = run_one(args.one, args.workers, args.duration, records, args.plots, args.scheduler)
        print("RESULT " + json.dumps(r))
        return
    print(f"motion: {'El Centro from ' + str(records) if records else 'the deck’s synthetic records'}; "
          f"duration {args.duration or 'the deck’s'} s; {args.workers} workers; load {os.getloadavg()}", flush=True)
    one_case_breakdown(args.duration, records)
    sizes = [int(x) for x in args.cases.split(",")]

    def sweep(n: int, scheduler: str | None = None) -> None:
        cmd = [sys.executable, __file__, "--one", str(n), "--workers", str(args.workers), "--records",
               str(args.records)]
        cmd += ["--duration", str(args.duration)] if args.duration is not None else []
        cmd += ["--plots"] if args.plots else []
        cmd += ["--scheduler", scheduler] if scheduler else []
        res = subprocess.run(cmd, capture_output=True, text=True)
        line = [x for x in res.stdout.splitlines() if x.startswith("RESULT ")]
        if res.returncode or not line:
            sys.exit(res.stdout + res.stderr)
        show(json.loads(line[0][7:]), args.workers)

    for n in sizes:
        sweep(n)
    if args.no_dask:
        return
    from distributed import LocalCluster

    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:  # this machine only
        for n in sizes:
            sweep(n, cluster.scheduler_address)


if __name__ == "__main__":
    main()
