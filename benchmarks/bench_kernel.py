"""Time-stepping kernel against a plain C loop of the same scheme, and the whole command.

    python benchmarks/bench_kernel.py [--deck decks/seed_wri.toml] [--repeat 30]

Builds chang_loop.c with the system's C compiler (gcc -O2), feeds it the seed scene's
arrays, checks that both give the same displacements, and prints the best times of
both over --repeat runs and the end-to-end time of `rbhyst run --no-plots`.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from rbhyst.solve import integrators  # noqa: E402
from rbhyst.model.deck import load_deck  # noqa: E402
from rbhyst.model.system import assemble  # noqa: E402
from rbhyst.model.settings import settings_from_deck  # noqa: E402
from rbhyst.solve.plan import _Buffers, prepare  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", default=str(ROOT / "decks" / "seed_wri.toml"))
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--cc", default=os.environ.get("CC", "gcc"))
    args = ap.parse_args()

    deck_path = Path(args.deck)
    deck = load_deck(deck_path)
    settings = settings_from_deck(deck)
    system = assemble(deck, deck_path.parent)
    plan = prepare(system, settings)  # compiles / loads the kernel
    n = plan.n_steps
    ne = system.bvec.shape[0]
    # like the C loop: the whole run as one chunk into the same output buffers every repeat
    t_grid = settings.dt * np.arange(n + 1)
    load = np.ascontiguousarray(system.excitation.load_nodes(t_grid, settings.dt, system.mass))
    buf = _Buffers(n, ne, system.n)
    times = []
    for _ in range(args.repeat):
        x, st = plan.initial_state()
        t0 = time.perf_counter()
        plan._call(load, 0.0, 1, settings.dt, 1, n, x, st, buf)
        times.append(time.perf_counter() - t0)
    t_numba = min(times)
    d_numba = buf.d.copy()
    e_hyst_numba = buf.e[-1, 2]
    t_simulate = min(plan.run().wall_s for _ in range(args.repeat))

    h = settings.dt
    coef = integrators.get("chang").coefficients(system.mass, system.K0, np.zeros((system.n, system.n)), h)
    t_grid = h * np.arange(n + 1)
    load = system.excitation.load(t_grid, system.mass)
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "chang_loop"
        subprocess.run([args.cc, "-O2", "-o", str(exe), str(HERE / "chang_loop.c"), "-lm"], check=True)
        parts = [f"{n} {system.bvec.shape[0]} {args.repeat} {h!r}"]
        for arr in (1.0 / system.mass, coef[0], coef[1], system.bvec, system.mult,
                    system.params.reshape(len(system.mult), 16), load):
            parts.append(" ".join(repr(float(x)) for x in np.ravel(arr)))
        proc = subprocess.run([str(exe)], input="\n".join(parts), capture_output=True, text=True, check=True)
    lines = proc.stdout.splitlines()
    t_c, e_in_c, e_hyst_c, _ = (float(x) for x in lines[0].split())
    d_c = np.array([[float(x) for x in line.split()] for line in lines[1:]])
    diff = np.max(np.abs(d_c - d_numba)) / np.max(np.abs(d_numba))

    rbhyst = shutil.which("rbhyst") or f"{sys.executable} -m rbhyst"
    cmd = rbhyst.split() + ["run", str(deck_path), "--no-plots", "--out", ""]
    with tempfile.TemporaryDirectory() as tmp:
        cmd[-1] = str(Path(tmp) / "out")
        subprocess.run(cmd, check=True, capture_output=True)  # warm the cache
        e2e = []
        for _ in range(5):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            e2e.append(time.perf_counter() - t0)

    print(f"scene: {deck_path.name}, {n} steps, {system.n_output_elements} elements "
          f"({system.bvec.shape[0]} distinct), integrator chang")
    print(f"numba kernel : {t_numba * 1e3:8.2f} ms (best of {args.repeat})")
    print(f"  simulate() : {t_simulate * 1e3:8.2f} ms wall_s (in chunks, with the load built per chunk)")
    print(f"plain C -O2  : {t_c * 1e3:8.2f} ms (best of {args.repeat})")
    print(f"ratio        : {t_numba / t_c:8.2f}")
    print(f"same answer  : max |d_C - d_numba| / max |d| = {diff:.2e}; "
          f"E_hyst {e_hyst_c:.10g} (C) vs {e_hyst_numba:.10g}")
    print(f"rbhyst run --no-plots end to end: best {min(e2e):.3f} s, median {np.median(e2e):.3f} s")


if __name__ == "__main__":
    main()
