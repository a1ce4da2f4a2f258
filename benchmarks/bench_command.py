"""The whole `rbhyst run` command on the seed deck, as a user starts it: wall time of the process.

    python benchmarks/bench_command.py [--deck decks/seed_wri.toml] [--repeat 5]

Runs the command once to warm the caches (numba's kernels, Python's bytecode, the disk), then
prints the median wall time of --repeat runs of

- `rbhyst run DECK --no-plots`,
- the same with the error estimate off (analysis.estimate_error = false, in a copy of the deck
  beside it), to show what the command costs apart from the estimate,
- `rbhyst run DECK` (with plots),

and then the import-time breakdown of `import rbhyst.cli` and of the run (`python -X importtime`):
the modules that cost most, their own time and with what they import. The outputs go to a
temporary folder.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def rbhyst_command() -> list[str]:
    """The installed `rbhyst` script beside this Python (what a user runs), else `python -m rbhyst`."""
    script = Path(sys.executable).parent / "rbhyst"
    return [str(script)] if script.exists() else [sys.executable, "-m", "rbhyst"]


def environment() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # a user's Python keeps the compiled bytecode
    return env


def wall(cmd: list[str], repeat: int) -> list[float]:
    """Wall times of `repeat` runs of `cmd` after one to warm up; a failing run stops the benchmark."""
    times = []
    for i in range(repeat + 1):
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, env=environment())
        t = time.perf_counter() - t0
        if done.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr}")
        if i:
            times.append(t)
    return times


def import_times(args: list[str]) -> list[tuple[str, int, int, int]]:
    """(module, own us, cumulative us, depth) of every import `python -X importtime ARGS` makes."""
    done = subprocess.run([sys.executable, "-X", "importtime", *args], capture_output=True, text=True,
                          env=environment())
    rows = []
    for line in done.stderr.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)", line)
        if m:
            rows.append((m.group(4), int(m.group(1)), int(m.group(2)), (len(m.group(3)) - 1) // 2))
    return rows


def breakdown(title: str, args: list[str], top: int = 15) -> None:
    """The top-level imports that cost most, and the total."""
    import_times(args)  # bytecode written
    rows = import_times(args)
    first = [r for r in rows if r[3] == 0]
    total = sum(r[2] for r in first)
    print(f"\n{title}: {total / 1e3:.0f} ms of imports, {len(rows)} modules")
    for name, _, cum, _ in sorted(first, key=lambda r: -r[2])[:top]:
        print(f"  {cum / 1e3:7.1f} ms  {name}")
    groups: dict[str, int] = {}
    for name, own, _, _ in rows:
        top_name = name.split(".")[0]
        groups[top_name] = groups.get(top_name, 0) + own
    print("  by package (own time of its modules):")
    for name, own in sorted(groups.items(), key=lambda kv: -kv[1])[:top]:
        print(f"  {own / 1e3:7.1f} ms  {name}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", default=str(ROOT / "decks" / "seed_wri.toml"))
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    deck = Path(args.deck).resolve()
    cmd = rbhyst_command()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        no_estimate = deck.parent / f".{deck.stem}-no-estimate{deck.suffix}"
        text = deck.read_text()
        if "[analysis]" not in text:
            text += "\n[analysis]\n"
        no_estimate.write_text(text.replace("[analysis]", "[analysis]\nestimate_error = false", 1))
        try:
            cases = [("--no-plots", [*cmd, "run", str(deck), "--no-plots", "--out", str(out)]),
                     ("--no-plots, estimate off", [*cmd, "run", str(no_estimate), "--no-plots", "--out", str(out)]),
                     ("with plots", [*cmd, "run", str(deck), "--out", str(out)])]
            print(f"rbhyst run {deck.name}: median of {args.repeat} warm runs (wall time of the process)")
            for label, c in cases:
                t = wall(c, args.repeat)
                shutil.rmtree(out, ignore_errors=True)
                print(f"  {label:26s} {statistics.median(t):.3f} s  (min {min(t):.3f}, max {max(t):.3f})")
        finally:
            no_estimate.unlink(missing_ok=True)
        breakdown("import rbhyst.cli", ["-c", "import rbhyst.cli"])
        breakdown(f"rbhyst run {deck.name} --no-plots",
                  ["-m", "rbhyst", "run", str(deck), "--no-plots", "--out", str(out)])


if __name__ == "__main__":
    main()
