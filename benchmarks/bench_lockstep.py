"""Cases stepped together, measured before they are built: B cases of the seed scene (each its
own support scale) stepped by Chang's method one after another, and the same B interleaved in
one compiled loop (every case's step k before any case's step k + 1: lockstep, each case's own
state), with the loop's own step code (rbhyst.solve.integrators.steps.chang_step, inlined).

    python benchmarks/bench_lockstep.py [--steps 32000] [--lanes 1,2,4,8,16] [--repeat 5]

Both loops give every case's displacements to the bit (checked), and they match the run's own
loop (plan.run at the same step, no substeps: checked on the first case). What the lockstep
gains is what interleaving alone gives (the processor overlapping independent cases' work); a
step whose element laws are written across lanes (vector lanes for the exponentials) would gain
more, and is what this measures the room for. Prints ns per case-step for each B.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
from numba import njit

from rbhyst.model.deck import load_deck
from rbhyst.results.analysis import scene
from rbhyst.solve.integrators.steps import chang_step
from rbhyst.solve.kernels.layout import N_W, W_A, W_AN, W_D, W_DN, W_V, W_VN, x_slice
from rbhyst.solve.plan import prepare

ROOT = Path(__file__).resolve().parents[1]


@njit(cache=False, error_model="numpy", inline="always")
def _step_lane(coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, cur, w, load, j, h, kpeak, bq, out_d):
    ok, bad, work = chang_step(coef, 0, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, cur, w, load, j,
                               0.0, 1.0, h, kpeak, bq)
    n = len(minv)
    for i in range(n):
        w[W_D, i] = w[W_DN, i]
        w[W_V, i] = w[W_VN, i]
        w[W_A, i] = w[W_AN, i]
        out_d[j, i] = w[W_D, i]
    return ok


@njit(cache=False, error_model="numpy")
def one_after_another(coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, w, loads, h, kpeak, bq, out_d):
    lanes, steps = loads.shape[0], loads.shape[1] - 1
    for b in range(lanes):
        cur = 0
        for j in range(steps):
            _step_lane(coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, st[b], cur, w[b], loads[b], j, h,
                       kpeak[b], bq[b], out_d[b])
            cur = 1 - cur


@njit(cache=False, error_model="numpy")
def lockstep(coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, w, loads, h, kpeak, bq, out_d):
    lanes, steps = loads.shape[0], loads.shape[1] - 1
    cur = 0
    for j in range(steps):
        for b in range(lanes):
            _step_lane(coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, st[b], cur, w[b], loads[b], j, h,
                       kpeak[b], bq[b], out_d[b])
        cur = 1 - cur


def lanes_of(planned, refine: int, scales: np.ndarray):
    """Each lane's load on the compute grid (its support scaled), state at rest and work space."""
    system, s = planned.system, planned.settings
    nsub = refine
    steps = planned.n_steps * nsub
    t = s.dt * (np.arange(steps + 1) / nsub)
    base = np.ascontiguousarray(system.excitation.load_nodes(t, s.dt / nsub, system.mass))
    x, st0 = planned.initial_state()
    ne, n = planned.bvec.shape
    b = len(scales)
    loads = np.ascontiguousarray(scales[:, None, None] * base[None])
    st = np.repeat(st0[None], b, axis=0)
    w = np.zeros((b, N_W, n))
    w[:, W_D] = x[x_slice(n, 0)]
    w[:, W_V] = x[x_slice(n, 1)]
    w[:, W_A] = x[x_slice(n, 2)] * scales[:, None]  # (at rest under the scaled load: the seed deck has no weight)
    return loads, st, w, np.zeros((b, ne, 2)), np.zeros((b, ne, n)), np.zeros((b, steps, n)), t


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", type=Path, default=ROOT / "decks" / "seed_wri.toml")
    ap.add_argument("--refine", type=int, default=4, help="compute steps per output step (the chosen pass's)")
    ap.add_argument("--lanes", default="1,2,4,8,16")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    deck = load_deck(args.deck)
    system, settings = scene(deck)
    s = dataclasses.replace(settings, integrator="chang", refine=args.refine, choose=False, duration=8.0)
    planned = prepare(system, s)
    assert planned.nsub == args.refine, "the record's substeps would split the grid: choose another refine"
    common = (planned.coef[args.refine], planned._mass, planned._minv, planned.cm, planned.damped, planned.bvec,
              planned.axial, system.rotation_index, system.mult, planned.params)
    h = s.dt / args.refine
    print(f"scene: {args.deck.name}, {planned.n_steps * args.refine} compute steps of {h:.3g} s, "
          f"{planned.bvec.shape[0]} element rows, n = {planned.bvec.shape[1]}")
    for b in [int(x) for x in args.lanes.split(",")]:
        scales = np.linspace(0.5, 1.5, b)
        best = {}
        outs = {}
        for name, fn in (("one after another", one_after_another), ("lockstep", lockstep)):
            times = []
            for _ in range(args.repeat + 1):  # (the first compiles)
                loads, st, w, kpeak, bq, out_d, t = lanes_of(planned, args.refine, scales)
                tic = time.perf_counter()
                fn(*common, st, w, loads, h, kpeak, bq, out_d)
                times.append(time.perf_counter() - tic)
            best[name] = min(times[1:])
            outs[name] = out_d
        assert np.array_equal(outs["lockstep"], outs["one after another"]), "lockstep changed a number"
        steps = b * planned.n_steps * args.refine
        seq, lock = best["one after another"], best["lockstep"]
        print(f"B = {b:3d}: one after another {seq / steps * 1e9:6.1f} ns, lockstep {lock / steps * 1e9:6.1f} ns "
              f"a case-step ({seq / lock:.2f}x)")
    # the lanes' step is the run's: the first lane at scale 1 against plan.run's rows at the same step
    loads, st, w, kpeak, bq, out_d, t = lanes_of(planned, args.refine, np.array([1.0]))
    lockstep(*common, st, w, loads, h, kpeak, bq, out_d)
    run = planned.run(keep=True)
    print(f"the run's own loop (rbhyst.solve.kernels.loop.run_chunk, its monitor and rows included): "
          f"{run.stats.wall_s / (planned.n_steps * args.refine) * 1e9:.1f} ns a step")
    if run.stats.substeps == 0:
        # (the rows hold d less the origin, as the table makes them from the loop's d)
        mine = out_d[0, args.refine - 1::args.refine] - planned.layout.origin[:system.n]
        theirs = run.table[1:, 1:1 + system.n]
        same = np.array_equal(mine, theirs)
        print(f"the run's own loop (no substeps): the same displacements to the bit: {same} "
              f"(largest difference {np.max(np.abs(mine - theirs)):.3g} m)")
    else:
        print(f"(the run split {run.stats.substeps} steps into substeps: not compared)")


if __name__ == "__main__":
    main()
