"""What stops cost the time-stepping kernel: the seed's scene as it is, with a stop on every element
beyond its peak deformation (never reached), and with stops it strikes.

    python benchmarks/bench_stops.py [--deck decks/seed_wri.toml] [--repeat 20] [--gap 0.004]

Prints, for each, the best kernel time over --repeat runs of the whole record in one chunk (as
bench_kernel.py), the substeps the stiffness monitor took and the impacts.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from rbhyst.model.deck import load_deck  # noqa: E402
from rbhyst.model.settings import settings_from_deck  # noqa: E402
from rbhyst.model.system import assemble  # noqa: E402
from rbhyst.solve.kernels.layout import NI, X_CUR, X_SUBSTEPS  # noqa: E402
from rbhyst.solve.plan import _Buffers, prepare  # noqa: E402


def with_stops(deck, gap: float, stiffness: float):
    """The deck with a stop at +-gap on every [[elements]] entry."""
    stop = {"gap": gap, "stiffness": stiffness, "restitution": 0.5}
    return deck.with_values({f"elements[{k}].stop": stop for k in range(1, len(deck.elements) + 1)})


def best(deck, base: Path, repeat: int) -> tuple[float, int, float]:
    """(best kernel seconds, substeps, impacts) of the whole run in one call of the loop."""
    settings = settings_from_deck(deck)
    system = assemble(deck, base)
    plan = prepare(system, settings)
    n = plan.n_steps
    t_grid = settings.dt * np.arange(n + 1)
    load = np.ascontiguousarray(system.excitation.load_nodes(t_grid, settings.dt, system.mass))
    buf = _Buffers(n, system.bvec.shape[0], system.n)
    times = []
    for _ in range(repeat):
        x, st = plan.initial_state()
        t0 = time.perf_counter()
        plan._call(load, 0.0, 1, settings.dt, 1, n, x, st, buf)
        times.append(time.perf_counter() - t0)
    return min(times), int(x[X_SUBSTEPS]), float(np.sum(st[int(x[X_CUR]), :, NI] * system.mult))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--deck", default=str(ROOT / "decks" / "seed_wri.toml"))
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--gap", type=float, default=0.004, help="m: where the struck stops are")
    ap.add_argument("--stiffness", type=float, default=5e6, help="N/m: the stops' K")
    args = ap.parse_args()
    path = Path(args.deck)
    deck = load_deck(path)
    cases = {"without stops": deck, "stops never reached (gap 1 m)": with_stops(deck, 1.0, args.stiffness),
             f"stops struck (gap {args.gap:g} m)": with_stops(deck, args.gap, args.stiffness)}
    base_time = None
    for name, d in cases.items():
        t, substeps, impacts = best(d, path.parent, args.repeat)
        base_time = base_time or t
        print(f"{name:34s} {t * 1e3:8.2f} ms ({t / base_time:.2f} x)  substeps {substeps:6d}  impacts {impacts:g}")


if __name__ == "__main__":
    main()
