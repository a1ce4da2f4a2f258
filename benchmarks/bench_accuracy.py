"""What the error estimate costs, and the work-precision table of every method.

    python benchmarks/bench_accuracy.py [--deck decks/seed_wri.toml --deck decks/cabinet_transformer.toml]

For each deck: a default run with and without the estimate (in one process, kernels loaded,
best of 3), then every fixed-step method at dt, dt/2, dt/4, dt/8 and the adaptive integration
at rtol 1e-6 ... 1e-10, each with its time stepping and its true error against the reference
(rtol 1e-12), and the estimate each reports.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def best(f, n=3):
    out = None
    t = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        out = f()
        t = min(t, time.perf_counter() - t0)
    return t, out


def main() -> None:
    import rbhyst
    from rbhyst.solve.estimate import relative_errors
    from rbhyst.solve.integrators import reference

    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", action="append")
    args = ap.parse_args()
    decks = args.deck or [str(ROOT / "decks" / "seed_wri.toml"), str(ROOT / "decks" / "cabinet_transformer.toml")]
    for path in decks:
        deck = rbhyst.load_deck(path)
        dt = deck.analysis.dt
        rbhyst.run(deck, estimate=False)
        t_off, plain = best(lambda: rbhyst.run(deck, estimate=False))
        t_on, res = best(lambda: rbhyst.run(deck))
        print(f"\n{Path(path).name}: {plain.steps} steps of {dt:g} s")
        print(f"  default run, no estimate: {t_off * 1e3:7.1f} ms (time stepping {plain.wall_s * 1e3:.1f} ms)")
        print(f"  default run with estimate: {t_on * 1e3:7.1f} ms (estimate {res.accuracy['wall_s'] * 1e3:.1f} ms: "
              f"{res.accuracy['reference']['steps']} adaptive steps, {res.accuracy['reference']['reversals']} reversals)")
        exact = reference.integrate(plain.system, plain.time, rtol=1e-12)
        print(f"  {'method':<20} {'setting':>12} {'stepping ms':>12} {'true error':>11} {'estimate':>10}")
        rows = [(m, f"dt {dt / 2**k:.3g}", dict(integrator=m, dt=dt / 2**k))
                for m in ("chang", "central-difference", "kr-alpha", "newmark") for k in range(4)]
        rows += [("adaptive", f"rtol {r:g}", dict(integrator="adaptive")) for r in (1e-6, 1e-8, 1e-10)]
        for name, label, kw in rows:
            d = deck if name != "adaptive" else deck.with_values({"analysis.rtol": float(label.split()[1])})
            w, r = best(lambda: rbhyst.run(d, **kw), n=2)
            k = round(dt / r.settings.dt)
            true = max(relative_errors(r.d[::k], exact.q, plain.system))
            est = max(r.accuracy["estimated_error"].values())
            print(f"  {name:<20} {label:>12} {r.wall_s * 1e3:12.1f} {true:11.2e} {est:10.2e}")


if __name__ == "__main__":
    main()
