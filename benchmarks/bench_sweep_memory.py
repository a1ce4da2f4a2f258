"""The memory of a large sweep's own process, without its computing: a store of N finished
cases (each a real case's journal line, its numbers jittered) and the sweep run on it with
``--redraw``, which reads the store and writes cases.csv, stats.csv, sweep.json and the plots,
as a computing sweep does after its last case.

    python benchmarks/bench_sweep_memory.py [--cases 10000,100000] [--no-plots]

Each N in a process of its own: its peak RSS (VmHWM, Linux), the time from the
store to the files, and the peak per case above a store of 1,000 cases. The seed deck under
El Centro (../shared/records beside the project; else its synthetic records), 5 scale factors
times N / 5 values of body.mass.
"""

from __future__ import annotations

import argparse
import json
import random
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

CHILD = r"""
import json, sys, time
from pathlib import Path
from rbhyst.sweep import load_sweep, run_sweep
sw = load_sweep(Path(sys.argv[1]))
tic = time.perf_counter()
outcome = run_sweep(sw, out=Path(sys.argv[2]), redraw=True, plots=sys.argv[3] == "plots")
took = time.perf_counter() - tic
# (VmHWM: this process's own peak; ru_maxrss also holds the parent's at the exec of a vfork)
hwm = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(json.dumps({"cases": len(sw.cases), "ok": outcome.ok, "s": took, "peak_mb": hwm / 1024}))
"""


def sweep_text(cases: int) -> str:
    from bench_sweep_batch import RECORDS, sweep_text as seed_sweep

    return seed_sweep(ROOT / "decks" / "seed_wri.toml", cases, RECORDS)


def make_store(path: Path, out: Path, template: dict) -> None:
    """The journal of every case of the sweep at ``path``, each line the template's with its key
    and its numbers jittered (distinct values, as real cases have)."""
    from rbhyst.analyses.sweep.store import Journal
    from rbhyst.sweep import load_sweep

    sw = load_sweep(path)
    rng = random.Random(1)
    journal = Journal(out)
    journal.open()
    block = []
    for c in sw.cases:
        e = {**template, "key": c.key}
        for g in ("peaks", "energy", "accuracy", "stroke"):
            e[g] = {k: (v * (1 + 0.1 * rng.random()) if isinstance(v, float) else v) for k, v in template[g].items()}
        block.append(e)
        if len(block) == 10_000:
            journal.add(block)
            journal.entries.clear()  # (this process's memory is not the one measured)
            block = []
    if block:
        journal.add(block)
    journal.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", default="10000,100000")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args()
    from rbhyst.analyses.sweep import worker
    from rbhyst.sweep import load_sweep

    sizes = [1000] + [int(float(x)) for x in args.cases.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        first = Path(tmp) / "one.toml"
        first.write_text(sweep_text(5))
        sw = load_sweep(first)
        template = worker.run_batch(sw.base, [(sw.cases[2].key, sw.cases[2].values)])[0]
        assert template["status"] == "ok", template
        base = None
        for n in sizes:
            path, out = Path(tmp) / f"s{n}.toml", Path(tmp) / f"out{n}"
            path.write_text(sweep_text(n))
            make_store(path, out, template)
            got = json.loads(subprocess.run([sys.executable, "-c", CHILD, str(path), str(out),
                                             "none" if args.no_plots else "plots"],
                                            check=True, capture_output=True, text=True).stdout.splitlines()[-1])
            per = "" if base is None else f", {(got['peak_mb'] - base) * 1024 / (n - 1000):.1f} kB a case above 1,000"
            print(f"{got['cases']:>7,} cases: {got['peak_mb']:7.0f} MB peak, {got['s']:6.1f} s from the store to "
                  f"the files{per}")
            if base is None:
                base = got["peak_mb"]


if __name__ == "__main__":
    main()
