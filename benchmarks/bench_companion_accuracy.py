"""How accurate a run's companion is as an answer, against the run itself at the same step.

The error estimate's companion (rbhyst.solve.companion) solves the scene with the method's own
error term taken out (-S) and every element's turn put where it falls within its step; the run
minus the companion is the run's error. The companion is then itself a solution of the scene,
to a higher order. This measures by how much: the seed deck's sweep cases (8 s of El Centro, the
support scaled), by Chang's method at dt / k, the run's and its companion's error at every
compute node against the adaptive reference at rtol 1e-12, column by column (G's displacements
u1 u2 theta3, its total accelerations at1 at2 alphat3, and the worst element force), each as its
largest difference over the run against the column's own peak; and the difference of the
companions at k and k / 2 (every other node of k), against the companion's error at k: what an
estimate of the companion's own error from two of them would say. The default run's chosen k
(rbhyst.solve.choose) is printed beside each case.

    python benchmarks/bench_companion_accuracy.py [--cases 4] [--k 1,2,4,8,16]

The records are the sweep benchmarks' (bench_sweep_batch.sweep_text: El Centro where the
shared records lie beside the project, else synthetic ones).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
COLUMNS = ("u1", "u2", "theta3", "at1", "at2", "alphat3", "e_f")


def errors(plan, tap, comp) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(run, companion): each column's largest error over the compute nodes over its peak; and
    the companion's columns at every node (d, at, element forces) with the reference's peaks."""
    from rbhyst.solve.integrators import reference

    (dd, _, df), _ = comp.run()
    exact = reference.integrate(plan.system, tap.t, rtol=1e-12).raw(plan.system)

    def columns(d, f):  # (support motion, small rotations: M at = -R, R = f rb)
        return np.hstack([d, -(f @ plan.rb) / plan.system.mass, f])

    ref = columns(exact.d, exact.f)
    peaks = np.max(np.abs(ref), axis=0)
    companion = columns(tap.d - dd, tap.f - df)
    run = columns(tap.d, tap.f)
    return worst(run, ref, peaks), worst(companion, ref, peaks), companion, peaks


def worst(x: np.ndarray, ref: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """Each of COLUMNS' largest |x - ref| over its peak (the element forces' worst as one)."""
    e = np.max(np.abs(x - ref), axis=0) / peaks
    return np.concatenate([e[:6], [e[6:].max()]])


def cells(errors: np.ndarray) -> str:
    return " ".join(f"{x:7.1e}" for x in errors)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=4)
    ap.add_argument("--k", default="1,2,4,8,16")
    args = ap.parse_args()
    from bench_sweep_batch import RECORDS, sweep_text

    from rbhyst.analyses.sweep import worker
    from rbhyst.results import analysis
    from rbhyst.solve.choose import compute_step
    from rbhyst.solve.companion import Companion, RunTap
    from rbhyst.solve.plan import prepare
    from rbhyst.sweep import load_sweep

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "s.toml"
        path.write_text(sweep_text(ROOT / "decks" / "seed_wri.toml", 5 * args.cases, RECORDS))
        sw = load_sweep(path)
    deck = sw.base.deck()
    picked = sw.cases[::5][:args.cases]  # (one of each scale level, in turn)
    print("error over the column's peak; " + " ".join(f"{c:>7}" for c in COLUMNS))
    for case in picked:
        d = deck.with_values(case.values)
        system, settings = analysis.scene(d)
        chosen, _ = worker.run_to_rest(d, keep=False)
        k_chosen = settings.dt / compute_step(chosen)
        scale = next(iter(case.values["excitation.support"].values()))["scale"]
        st = chosen.stats
        print(f"scale {scale:g} (the default run: k = {k_chosen:g}, {st.steps * st.record_substeps * st.refine} "
              f"compute steps in its last pass)")
        before = None  # (k, the companion's columns at k)
        for k in map(int, args.k.split(",")):
            s = dataclasses.replace(settings, integrator="chang", choose=False, dt=settings.dt / k,
                                    every=settings.every * k)
            plan = prepare(system, s)
            tap = RunTap(plan)
            plan.run(keep=False, tap=tap)
            run, comp, columns, peaks = errors(plan, tap, Companion(plan, tap, 1))
            print(f"  k = {k:2d}  run        {cells(run)}\n          companion  {cells(comp)}   "
                  f"(worst {run.max() / comp.max():.1f} x smaller)")
            if before is not None and 2 * before[0] == k:
                # the difference of two companions a step apart (the nodes of k / 2 are every other
                # node of k): what an estimate of the companion's own error would take, over its error
                diff = worst(columns[::2], before[1], peaks)
                print(f"          |c(k) - c(k/2)| {cells(diff)}   (the worst {diff.max() / comp.max():.1f} x the "
                      f"companion's error at k)")
            before = (k, columns)


if __name__ == "__main__":
    main()
