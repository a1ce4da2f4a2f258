"""Sweep throughput side by side with rbhyst 0.2, in one run on one machine: the seed deck over
8 s of El Centro, scale factors and body.mass varying (every case computed, none reused), on
local workers, each case with its error estimate.

    python benchmarks/bench_sweep_batch.py [--cases 10000] [--workers 2] [--old PYTHON]
                                           [--records DIR] [--check 20] [--dask] [--only NAMES]

Sweeps (each ``rbhyst sweep FILE --workers W --no-plots`` in a process of its own; --only picks):

- ``0.2``: rbhyst 0.2 (``--old``: a Python whose rbhyst is 0.2; ``git worktree add`` of the
  tag and ``pip install`` into a venv of its own) on 0.2's seed deck: chang at exactly dt =
  1 ms, its estimate;
- ``0.2-fine``: 0.2 at the compute step this tree chooses for the seed deck's case at scale 1
  (dt = 0.125 ms, every 8th row written: the 1 ms rows), where chang meets 1 % as this tree's
  chosen cases do: 0.2 at equal accuracy (a 0.2 user had to pick that step by hand);
- ``fixed``: this tree on the same settings (``integrator = "chang"``: the same work as 0.2's
  case);
- ``chosen``: this tree on its own seed deck (rbhyst chooses the compute step that meets
  warn_error: some 5 to 9 times 0.2's steps, and a screening pass);
- ``dask``: ``chosen`` on a local Dask cluster of W single-threaded workers (with ``--dask``):
  its peaks are compared with ``chosen``'s, case by case.

``--rounds R`` runs them R times in turn, each compared with 0.2's fastest round so far.
Reported per sweep: wall time, cases per second, the ratio to 0.2's cases per second, and the
peak resident memory of the sweep's process tree (the sum over the sweep and its workers,
sampled every 0.2 s; a Dask cluster's workers are not the sweep's children and not counted). ``--check K``: K cases of each of this tree's sweeps run alone
(``rbhyst.run``), their peaks against the sweep's: the largest relative difference.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"
RECORDS = ROOT.parent / "shared" / "records"
OLD_TAG = "c0d4750"  # version 0.2.0


def sweep_text(deck: Path, n: int, records: Path, levels: int = 5) -> str:
    """A sweep of n cases (n a multiple of ``levels``): 8 s of El Centro at ``levels`` scale
    factors from 0.5 to 1.5 times n / levels values of body.mass."""
    per = max(1, n // levels)
    factors = ", ".join(repr(round(0.5 + k / max(1, levels - 1), 6)) for k in range(levels))
    masses = ", ".join(repr(800.0 + 0.01 * k) for k in range(per))
    return (f'deck = "{deck.as_posix()}"\n\n[[motions]]\nname = "elc"\n'
            f'x1 = {{ file = "{(records / "I-ELC270.AT2").as_posix()}", units = "g" }}\n'
            f'x2 = {{ file = "{(records / "I-ELC180.AT2").as_posix()}", units = "g" }}\n\n'
            f'[scale]\nfactors = [{factors}]\n\n'
            f'[vary]\n"analysis.duration" = [8.0]\n"body.mass" = [{masses}]\n')


def old_deck_text() -> str:
    """0.2's seed deck (from git: the tag's decks/seed_wri.toml)."""
    return subprocess.run(["git", "-C", str(ROOT), "show", f"{OLD_TAG}:decks/seed_wri.toml"], check=True,
                          capture_output=True, text=True).stdout


def old_fine_deck_text() -> str:
    """0.2's seed deck at dt = 0.125 ms, every 8th row written."""
    text = old_deck_text()
    assert "\ndt = 0.001\n" in text and "\n[output]\n" in text
    return text.replace("\ndt = 0.001\n", "\ndt = 0.000125\n").replace("\n[output]\n", "\n[output]\nevery = 8\n")


def fixed_deck_text() -> str:
    """This tree's seed deck at 0.2's settings: chang at exactly dt."""
    text = DECK.read_text()
    assert '# integrator = "chang"' in text
    return text.replace('# integrator = "chang"', 'integrator = "chang"')


def tree_rss(pid: int) -> int:
    """Resident bytes of a process and its descendants."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            with open(f"/proc/{p}/status") as fh:
                total += next(int(x.split()[1]) * 1024 for x in fh if x.startswith("VmRSS:"))
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as fh:
                    todo.extend(int(x) for x in fh.read().split())
        except (OSError, StopIteration):
            pass
    return total


def timed_sweep(python: str, env: dict, sweep: Path, out: Path, workers: int, scheduler: str | None) -> dict:
    cmd = [python, "-m", "rbhyst", "sweep", str(sweep), "--out", str(out), "--no-plots", "--fresh"]
    cmd += ["--scheduler", scheduler] if scheduler else ["--workers", str(workers)]
    peak = [0]
    tic = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def sample():
        while proc.poll() is None:
            peak[0] = max(peak[0], tree_rss(proc.pid))
            time.sleep(0.2)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    text = proc.communicate()[0]
    wall = time.perf_counter() - tic
    sampler.join()
    if proc.returncode:
        sys.exit(f"{' '.join(cmd)} failed:\n{text}")
    return {"wall_s": wall, "peak_mb": peak[0] / 2**20, "last": text.strip().splitlines()[-2:]}


def journal_peaks(out: Path) -> dict[str, dict]:
    lines = (out / ".rbhyst-sweep" / "journal.jsonl").read_text().splitlines()[1:]
    return {e["key"]: e["peaks"] for e in map(json.loads, lines) if e.get("status") == "ok"}


def relative_gap(a: dict, b: dict) -> float:
    """The largest |a - b| / max(|b|, 1e-300) over the peaks both hold."""
    keys = [k for k in b if a.get(k) is not None and b[k] is not None]
    return max((abs(a[k] - b[k]) / max(abs(b[k]), 1e-300) for k in keys), default=0.0)


def check_alone(sweep: Path, out: Path, k: int) -> float:
    """The largest relative difference of k cases' peaks (spread over the sweep) from the same
    cases run alone (rbhyst.run), in this process."""
    import warnings

    import rbhyst
    from rbhyst.sweep import load_sweep

    sw = load_sweep(sweep)
    peaks = journal_peaks(out)
    picked = sw.cases[:: max(1, len(sw.cases) // k)][:k]
    base = sw.base.deck()
    with warnings.catch_warnings():  # (the fixed step's accuracy warnings: the sweep's cases say them too)
        warnings.simplefilter("ignore")
        return max(relative_gap(peaks[c.key], rbhyst.run(base.with_values(c.values)).summary()["peaks"])
                   for c in picked)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--old", default=None, help="a Python whose rbhyst is 0.2 (default: none, 0.2 left out)")
    ap.add_argument("--records", type=Path, default=RECORDS, help="the folder of I-ELC270.AT2 and I-ELC180.AT2")
    ap.add_argument("--check", type=int, default=20, help="cases of each sweep run alone and compared (0: none)")
    ap.add_argument("--dask", action="store_true", help="also the chosen sweep on a local Dask cluster")
    ap.add_argument("--rounds", type=int, default=1,
                    help="run the sweeps this many times in turn (a shared machine's load then falls on all)")
    ap.add_argument("--only", default=None, help="comma-separated: of 0.2, 0.2-fine, fixed, chosen, dask")
    args = ap.parse_args()
    if not (args.records / "I-ELC270.AT2").is_file():
        sys.exit(f"{args.records}: no El Centro records there (--records)")
    names = ["0.2", "0.2-fine"] * bool(args.old) + ["fixed", "chosen"] + ["dask"] * args.dask
    if args.only:
        names = [x for x in names if x in args.only.split(",")]
    runs = names * args.rounds
    here = os.environ.copy()
    here["PYTHONPATH"] = str(ROOT) + os.pathsep + here.get("PYTHONPATH", "")
    print(f"{args.cases} cases, {args.workers} workers; load {os.getloadavg()}", flush=True)
    results: dict[str, dict] = {}  # (each sweep's fastest round)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        shutil.copytree(DECK.parent / "records", folder / "records")  # (the decks' own records, overridden)
        decks = {"0.2": old_deck_text, "0.2-fine": old_fine_deck_text, "fixed": fixed_deck_text, "chosen": DECK.read_text}
        cluster = None
        if "dask" in names:
            from distributed import LocalCluster

            cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None)
        try:
            for k, name in enumerate(runs):
                deck = folder / f"seed_{name if name != 'dask' else 'chosen'}.toml"
                if not deck.exists():
                    deck.write_text(decks[name]())
                sweep = folder / f"{name}.toml"
                sweep.write_text(sweep_text(deck, args.cases, args.records))
                python, env = (args.old, os.environ.copy()) if name.startswith("0.2") else (sys.executable, here)
                r = timed_sweep(python, env, sweep, folder / name, args.workers,
                                cluster.scheduler_address if name == "dask" else None)
                r["per_s"] = args.cases / r["wall_s"]
                if name not in results or r["wall_s"] < results[name]["wall_s"]:
                    results[name] = r
                line = (f"{name:>6}: {r['wall_s']:8.1f} s, {r['per_s']:7.1f} cases/s, peak {r['peak_mb']:5.0f} MB "
                        f"({'the sweep; its Dask workers not counted' if name == 'dask' else 'the sweep and its workers'})")
                for ref in ("0.2", "0.2-fine"):
                    if ref in results and not name.startswith("0.2"):
                        line += f", {r['per_s'] / results[ref]['per_s']:.2f} x {ref}'s fastest cases/s so far"
                if not name.startswith("0.2") and args.check and k < len(names):  # (the first round's)
                    line += f"; {args.check} cases alone: peaks within {check_alone(sweep, folder / name, args.check):.2g}"
                if name == "dask" and "chosen" in results:
                    a, b = journal_peaks(folder / "dask"), journal_peaks(folder / "chosen")
                    same = sum(a[k] == b.get(k) for k in a)
                    line += f"; {same} of {len(a)} cases' peaks equal to the local sweep's"
                print(line, "\n         " + " | ".join(r["last"]), flush=True)
        finally:
            if cluster is not None:
                cluster.close()


if __name__ == "__main__":
    main()
