"""A finished sweep run again: `rbhyst sweep` on a folder that holds every case, against its
first run.

    python benchmarks/bench_sweep_again.py [--levels 4] [--masses 48] [--duration 8] [--workers 2]

The seed deck under El Centro (I-ELC270 along x1, I-ELC180 along x2, from ../shared/records
beside the project, else the deck's synthetic records), ``--levels`` scale factors times
``--masses`` values of body.mass (4 x 48 = 192 cases), each sweep a process of its own timed
whole: the first run, the run again that computes nothing (its files standing), and the same
with ``--redraw`` (tables and figures written again).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"
RECORDS = ROOT.parent / "shared" / "records"


def sweep_file(folder: Path, levels: int, masses: int, duration: float) -> Path:
    text = f'deck = "{DECK.as_posix()}"\n\n'
    if (RECORDS / "I-ELC270.AT2").is_file():
        text += ('[[motions]]\nname = "elc"\n'
                 f'x1 = {{ file = "{(RECORDS / "I-ELC270.AT2").as_posix()}", units = "g" }}\n'
                 f'x2 = {{ file = "{(RECORDS / "I-ELC180.AT2").as_posix()}", units = "g" }}\n\n')
    factors = ", ".join(repr(0.5 * (k + 1)) for k in range(levels))
    text += f"[scale]\nfactors = [{factors}]\n\n[vary]\n"
    text += f'"analysis.duration" = [{float(duration)!r}]\n'
    text += f'"body.mass" = [{", ".join(repr(800.0 + k) for k in range(masses))}]\n'
    path = folder / "again.toml"
    path.write_text(text)
    return path


def timed(args: list[str]) -> tuple[float, str]:
    tic = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "rbhyst", "sweep", *args], capture_output=True, text=True,
                          check=True)
    return time.perf_counter() - tic, done.stderr.strip().splitlines()[-1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", type=int, default=4)
    ap.add_argument("--masses", type=int, default=48)
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = sweep_file(Path(tmp), a.levels, a.masses, a.duration)
        common = [str(path), "--workers", str(a.workers), "--out", str(Path(tmp) / "out")]
        first, _ = timed(common)
        again, said = timed(common)
        redraw, _ = timed([*common, "--redraw"])
        print(f"{a.levels * a.masses} cases: first run {first:.2f} s; run again {again:.2f} s "
              f"({again / first:.3f} of the first; {said}); with --redraw {redraw:.2f} s")


if __name__ == "__main__":
    main()
