"""Peak memory of a streamed run (`rbhyst run DECK --out DIR --no-plots`) against its rows: the
seed deck on its synthetic records, rows of dt over 40 s and beyond (the records end at 40 s,
the body then rings down at rest), with and without its error estimate.

    python benchmarks/bench_memory.py [--rows 1e5,4e5,2e6] [--every 1] [--no-estimate-too] [--integrator adaptive]

Each run is a process of its own; its peak resident memory is the kernel's (ru_maxrss from
wait4 of that process alone). ``--every 10 --rows 2e7`` is the issue's 20 million steps with
every tenth row written; ``--integrator adaptive`` streams the adaptive integration's rows a window
at a time. A streamed run should peak at the same memory whatever its rows.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"
SECONDS = 40.0  # the records' length


def deck_text(rows: int, every: int, estimate: bool, integrator: str | None = None) -> str:
    """The seed deck at dt = 40 s / rows (at most 0.1 ms: longer runs take a longer duration)."""
    steps = rows * every
    dt = max(SECONDS / steps, 1e-4)
    text = DECK.read_text()
    records = (DECK.parent / "records").as_posix()
    text = text.replace('file = "records/', f'file = "{records}/')
    extra = f"dt = {dt!r}\nduration = {steps * dt!r}\nestimate_error = {'true' if estimate else 'false'}\n"
    text = re.sub(r"^dt = .*$", extra.rstrip("\n"), text, count=1, flags=re.M)
    if integrator:
        extra = f"integrator = \"{integrator}\"\n"
        text = re.sub(r"^dt = ", extra + "dt = ", text, count=1, flags=re.M)
    return text.replace("[output]\n", f"[output]\nevery = {every}\n")


def peak_of(deck: Path, out: Path) -> tuple[float, float, str, str]:
    """(peak RSS in MB, wall s, the run's line of its steps, what its error was estimated against:
    the companion, the adaptive solution, none) of one run in its own process."""
    tic = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "rbhyst", "run", str(deck), "--out", str(out), "--no-plots"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    text = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"rbhyst run {deck} ended with {proc.returncode}")
    line = next((s for s in text.splitlines() if " steps in " in s), "")
    accuracy = json.loads((out / "summary.json").read_text()).get("accuracy") or {}
    method = accuracy.get("method", "none")
    against = "companion" if "companion" in method else "adaptive" if "adaptive" in method else method.split()[0]
    return usage.ru_maxrss / 1024, time.perf_counter() - tic, line.split(";")[0], against


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", default="1e5,4e5,2e6")
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--no-estimate-too", action="store_true", help="each also with estimate_error = false")
    ap.add_argument("--integrator", default=None, help="the deck's integrator (default: the deck's choice)")
    a = ap.parse_args()
    print(f"{'rows':>10} {'every':>5} {'estimate':>8} {'against':>9} {'peak RSS MB':>11} {'wall s':>7}  run")
    with tempfile.TemporaryDirectory() as tmp:
        for rows in (int(float(x)) for x in a.rows.split(",")):
            for estimate in (True, False) if a.no_estimate_too else (True,):
                deck = Path(tmp) / f"m{rows}.toml"
                deck.write_text(deck_text(rows, a.every, estimate, a.integrator))
                mb, wall, line, against = peak_of(deck, Path(tmp) / f"out{rows}")
                print(f"{rows:>10} {a.every:>5} {str(estimate):>8} {against:>9} {mb:>11.0f} {wall:>7.2f}  {line}",
                      flush=True)


if __name__ == "__main__":
    main()
