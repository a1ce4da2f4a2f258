"""How often a default run is right the first time, and what it costs against the seed's method.

    python benchmarks/bench_default.py [--plane 40] [--pulses 40] [--space 12] [--repeat 1]

Random scenes of every kind: the plane body under sines and shocks at a careful or a lazy dt
(tests/test_accuracy.py's generator, seeds 1000...), under pulses on and off the step grid,
sines that stop off zero, records and forces, some with a damper (tests/test_accelerations.py's,
seeds 4000..., without its spectra), and boxes in space on four isolators under sines and
pulses along all three axes (seeds 7000...). For each, the default run (no integrator named,
kinematics "auto") against the body's exact motion (exact kinematics, the adaptive integration
at rtol 1e-12, on the run's rows, every column the estimate covers):

- right: no warning at all and every output within 2 % (a column the scene leaves nearly at
  rest, below a tenth of its family's scale, judged in its family's terms as the warnings judge);
- silent: no warning and some output more than 2 % off (the count that must be 0);
- its computing: analysis.chosen.computing_wall_s (every pass's time stepping and estimate, the
  answer's included: what analysis.wall_s + accuracy.wall_s are of one run) against the same
  deck with ``integrator="chang"`` at its dt (analysis.wall_s + accuracy.wall_s); and the whole
  ``rbhyst.run`` call of each (planning, Python and the kinematics' twin included).

Then the Quick start's ``rbhyst run decks/seed_wri.toml --no-plots`` as a whole command, by
default and with ``--integrator chang`` (the median of 5 of each, interleaved).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def truth_errors(res) -> dict[str, float]:
    """Every column's error against the body's exact motion (the tests' measure; tests/ is on
    the path: main)."""
    from test_right_first_time import errors_against_exact_motion

    return errors_against_exact_motion(res)


def space_scene(rng: np.random.Generator) -> dict:
    """A box of random size and mass on four isolators of one random VRM set per direction
    under a sine or a pulse along one to three axes, at a careful or a lazy dt."""
    sx, sy, sz = (float(v) for v in rng.uniform([0.3, 0.3, 0.4], [1.0, 1.0, 2.5]))
    mass = float(10 ** rng.uniform(1.5, 3.0))

    def vrm(scale):
        k = mass * (2 * np.pi * rng.uniform(2, 10)) ** 2 / 4 * scale
        alpha = float(10 ** rng.uniform(1.5, 3.0))
        return {"loading": {"kb": 0.1 * k, "f0": 0.9 * k / alpha, "alpha": alpha},
                "unloading": {"kb": 0.1 * k, "f0": 0.9 * k / alpha, "alpha": alpha}}

    isolators = [{"vertex": v, "axial": [0.0, 0.0, -1.0], "hysteresis": {"axial": "ax", "shear": "sh"}}
                 for v in (1, 2, 3, 4)]
    support = {}
    for axis in rng.choice(["x1", "x2", "x3"], size=int(rng.integers(1, 4)), replace=False):
        if rng.random() < 0.5:
            support[str(axis)] = {"type": "sine", "amplitude": float(rng.uniform(0.1, 0.8)), "units": "g",
                                  "frequency_hz": float(rng.uniform(1, 10)), "cycles": float(rng.integers(2, 6))}
        else:
            support[str(axis)] = {"type": str(rng.choice(["half-sine", "terminal-peak-sawtooth"])), "units": "g",
                                  "amplitude": float(rng.uniform(2, 15)), "duration": float(rng.uniform(0.005, 0.02)),
                                  "start": float(rng.uniform(0.01, 0.05))}
    return {"body": {"box": {"size": [sx, sy, sz], "centre": [sx / 2, sy / 2, sz / 2]}, "mass": mass},
            "hysteresis": {"ax": vrm(1.0), "sh": vrm(0.4)}, "isolators": isolators,
            "excitation": {"support": support},
            "output": {"points": [{"name": "top", "point": [0.0, 0.0, sz]}]},
            "analysis": {"dt": float(rng.choice([5e-4, 2e-3, 5e-3])), "duration": 1.5}}


def scenes(args, tmp: Path):
    sys.path.insert(0, str(ROOT / "tests"))
    from test_accelerations import random_scene as pulses
    from test_accuracy import random_scene as plane

    for seed in range(args.plane):
        yield f"plane {1000 + seed}", plane(np.random.default_rng(1000 + seed))
    for seed in range(args.pulses):
        folder = tmp / f"p{seed}"
        folder.mkdir()
        data = pulses(np.random.default_rng(4000 + seed), folder)
        data.pop("output", None)  # (their spectra: estimated by the adaptive solutions, another bench)
        yield f"pulses {4000 + seed}", data, folder
    for seed in range(args.space):
        yield f"space {7000 + seed}", space_scene(np.random.default_rng(7000 + seed))


def main() -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    ap = argparse.ArgumentParser()
    ap.add_argument("--plane", type=int, default=40)
    ap.add_argument("--pulses", type=int, default=40)
    ap.add_argument("--space", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=1, help="runs of each for its time, the best counted")
    ap.add_argument("--no-command", action="store_true", help="skip the Quick start's command")
    args = ap.parse_args()
    import rbhyst
    from conftest import write_deck

    from rbhyst.solve.estimate import family_terms, ranked

    warnings.simplefilter("ignore")
    rbhyst.run(ROOT / "decks" / "seed_wri.toml")  # kernels loaded
    tmp = Path(tempfile.mkdtemp())
    rows = []
    print(f"{'scene':<14} {'right':>5} {'warned':>6} {'true':>8} {'est':>8} {'kin':>5} {'passes':>6} "
          f"{'default ms':>10} {'chang ms':>9} {'ratio':>6} {'call':>6}")
    for item in scenes(args, tmp):
        name, data = item[0], item[1]
        folder = item[2] if len(item) > 2 else tmp
        path = write_deck(folder, data, name.replace(" ", "_"))
        try:
            rbhyst.load_deck(path).with_values({})  # (a generator's self-intersecting polygon: not a scene)
            from rbhyst.results.analysis import scene

            scene(rbhyst.load_deck(path))
        except rbhyst.InputError as err:
            print(f"{name:<14} not a scene: {str(err)[:90]}")
            continue
        try:
            best_d, best_c, call_d, call_c = np.inf, np.inf, np.inf, np.inf
            for _ in range(args.repeat):
                tic = time.perf_counter()
                res = rbhyst.run(path)
                call_d = min(call_d, time.perf_counter() - tic)
                best_d = min(best_d, res.chosen["computing_wall_s"] if res.chosen else res.wall_s + res.accuracy["wall_s"])
                tic = time.perf_counter()
                chang = rbhyst.run(path, integrator="chang")
                call_c = min(call_c, time.perf_counter() - tic)
                best_c = min(best_c, chang.wall_s + (chang.accuracy or {}).get("wall_s", 0.0))
        except rbhyst.AnalysisError as err:
            print(f"{name:<14} refused: {str(err)[:90]}")
            rows.append((name, False, True, False, np.nan, np.nan, np.nan))
            continue
        errors = truth_errors(res)
        true = max(errors.values())
        # (judged as the warnings judge: a column the scene leaves nearly at rest, below a tenth of
        # its family's scale, by its error in its family's terms; rbhyst.solve.estimate.ranked)
        off = ranked(errors, 0.02, *family_terms(errors, res))
        est = max((v for k, v in (res.accuracy or {}).get("estimated_error", {}).items()), default=np.nan)
        warned = bool(res.warnings)
        right = not warned and not off
        passes = len(res.chosen["passes"]) if res.chosen else 0
        rows.append((name, right, warned, bool(off), best_d / best_c, est, call_d / call_c))
        print(f"{name:<14} {'yes' if right else 'no':>5} {'yes' if warned else 'no':>6} {true:8.2e} {est:8.2e} "
              f"{res.system.kinematics:>5} {passes:6d} {best_d * 1e3:10.2f} {best_c * 1e3:9.2f} {best_d / best_c:6.2f}"
              f" {call_d / call_c:6.2f}"
              + ("   " + res.warnings[0][:100] if warned else ""))
    n = len(rows)
    right = sum(r[1] for r in rows)
    silent = [r[0] for r in rows if not r[2] and r[3]]
    ratios = [r[4] for r in rows if np.isfinite(r[4])]
    calls = [r[6] for r in rows if np.isfinite(r[6])]
    print(f"\n{n} scenes: {right} right the first time ({right / n:.0%}), {sum(r[2] for r in rows)} warned, "
          f"{len(silent)} silent {silent}; computing default / chang-at-dt: median {np.median(ratios):.2f}x "
          f"(quartiles {np.percentile(ratios, 25):.2f}-{np.percentile(ratios, 75):.2f}); the whole rbhyst.run "
          f"call: median {np.median(calls):.2f}x")
    if not args.no_command:
        deck = ROOT / "decks" / "seed_wri.toml"
        walls = {"default": [], "--integrator chang": []}
        for _ in range(5):
            for label in walls:
                extra = [] if label == "default" else ["--integrator", "chang"]
                tic = time.perf_counter()
                subprocess.run(["rbhyst", "run", str(deck), "--no-plots", "--out", str(tmp / "cmd"), *extra],
                               check=True, capture_output=True)
                walls[label].append(time.perf_counter() - tic)
        d, c = np.median(walls["default"]), np.median(walls["--integrator chang"])
        print(f"rbhyst run decks/seed_wri.toml --no-plots: default {d:.3f} s, --integrator chang {c:.3f} s "
              f"({d / c:.2f}x)")


if __name__ == "__main__":
    main()
