"""Where a sweep case's time goes: the seed deck's cases (8 s of El Centro, body.mass and the
scale varying) through the sweep worker (rbhyst.analyses.sweep.worker.run_batch), the time of
each phase added up over the cases and given per case.

    python benchmarks/profile_sweep_case.py [--cases 200] [--records DIR] [--cprofile 30]

Phases (wall time, the innermost phase counted where phases nest): deck values
(Deck.with_values), scene (assemble), plan (prepare: grid, coefficients), stepping (the
compiled loop's seconds: every pass's RunStats.wall_s), rows (the stepping's Python: the
chunks' tables and reductions, plan.run less the loop), estimate (the error estimate, its
companion's kernels included, and the companion stepped alongside the run), kinematics (the small rotations' neglected terms), checks
(diagnose, warnings) and the rest (the case's dict, the choice's bookkeeping). ``--cprofile N``
prints the N functions of most own time as well; ``--fixed`` takes 0.2's settings (chang at dt).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time
from collections import defaultdict
from pathlib import Path

from bench_sweep_batch import sweep_text  # (the same sweep as the side-by-side's)

ROOT = Path(__file__).resolve().parents[1]
DECK = ROOT / "decks" / "seed_wri.toml"
RECORDS = ROOT.parent / "shared" / "records"


class Phases:
    """Wall time per phase; a phase entered inside another is taken out of the outer one."""

    def __init__(self):
        self.s = defaultdict(float)
        self._stack: list[list] = []

    def wrap(self, name, fn):
        def timed(*a, **kw):
            frame = [name, time.perf_counter(), 0.0]  # (name, start, time of inner phases)
            self._stack.append(frame)
            try:
                return fn(*a, **kw)
            finally:
                self._stack.pop()
                took = time.perf_counter() - frame[1]
                self.s[name] += took - frame[2]
                if self._stack:
                    self._stack[-1][2] += took
        return timed

    def credit(self, name, seconds, out_of):
        """``seconds`` of the phase ``out_of`` were ``name``'s (the kernel's own clock)."""
        self.s[name] += seconds
        self.s[out_of] -= seconds


def instrument(ph: Phases) -> None:
    from rbhyst.analyses.sweep import worker
    from rbhyst.model import deck as deck_mod
    from rbhyst.results import analysis, checks
    from rbhyst.solve import alongside, choose, companion, estimate, kinematic, plan

    deck_mod.Deck.with_values = ph.wrap("deck values", deck_mod.Deck.with_values)
    analysis.scene = ph.wrap("scene", analysis.scene)
    plan.prepare = ph.wrap("plan", plan.prepare)
    run = plan.FixedStepPlan.run

    def stepped(self, *a, **kw):
        r = run(self, *a, **kw)
        ph.credit("stepping (kernel)", r.stats.wall_s, "rows (stepping's Python)")
        return r

    plan.FixedStepPlan.run = ph.wrap("rows (stepping's Python)", stepped)
    estimate.estimate = ph.wrap("estimate", estimate.estimate)
    # the companion stepped with the run (a tap of its chunks) is the estimate's too
    companion.RunTap.__call__ = ph.wrap("estimate", companion.RunTap.__call__)
    alongside.Alongside.__call__ = ph.wrap("estimate", alongside.Alongside.__call__)
    for name in ("kinematics_summary", "needs_exact"):
        setattr(kinematic, name, ph.wrap("kinematics", getattr(kinematic, name)))
    checks.diagnose = ph.wrap("checks", checks.diagnose)
    analysis.diagnose = checks.diagnose
    worker.run_case = ph.wrap("rest", worker.run_case)
    choose.estimated_run.__globals__["prepare"] = plan.prepare


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--records", type=Path, default=RECORDS)
    ap.add_argument("--fixed", action="store_true", help='the deck at 0.2\'s settings: integrator = "chang" at dt')
    ap.add_argument("--cprofile", type=int, default=0, help="also print the N functions of most own time")
    args = ap.parse_args()
    import shutil
    import tempfile

    from rbhyst.analyses.sweep import worker
    from rbhyst.sweep import load_sweep

    with tempfile.TemporaryDirectory() as tmp:
        path, deck = Path(tmp) / "profile.toml", DECK
        if args.fixed:
            deck = Path(tmp) / "seed_fixed.toml"
            deck.write_text(DECK.read_text().replace('# integrator = "chang"', 'integrator = "chang"'))
            shutil.copytree(DECK.parent / "records", Path(tmp) / "records")
        path.write_text(sweep_text(deck, args.cases, args.records))
        sw = load_sweep(path)
    base, todo = sw.base, [(c.key, c.values) for c in sw.cases]
    worker.run_batch(base, todo[:3])  # kernels loaded, records read
    ph = Phases()
    instrument(ph)
    tic = time.perf_counter()
    out = worker.run_batch(base, todo)
    wall = time.perf_counter() - tic
    assert all(o["status"] == "ok" for o in out), [o.get("message") for o in out if o["status"] != "ok"]
    n = len(todo)
    print(f"{n} cases in one process: {wall / n * 1e3:.2f} ms a case")
    for name, s in sorted(ph.s.items(), key=lambda x: -x[1]):
        print(f"  {name:<26} {s / n * 1e3:7.2f} ms  {s / wall:6.1%}")
    if args.cprofile:
        pr = cProfile.Profile()
        pr.enable()
        worker.run_batch(base, todo)
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(args.cprofile)


if __name__ == "__main__":
    main()
