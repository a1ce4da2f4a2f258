"""Accuracy against cost: every integrator at every dt against the reference solution.

``run_study`` integrates the scene with each fixed-step integrator at each dt, times
the time stepping alone (the kernel is compiled or loaded before the clock starts,
best of a few repeats for short runs), and measures the error of every coordinate of the
body (u1, u2 and theta3 in the plane; u1, u2, u3, theta1, theta2, theta3 in space)
against one reference solution (:mod:`rbhyst.solve.integrators.reference`) as a relative
max-norm, max_t |q - q_ref| / max_t |q_ref|. The observed order of each integrator is
the least-squares slope of log error against log dt over its asymptotic range.

No terminal and no plots here: progress goes to a callback, plots live in
:mod:`rbhyst.report.study`, files are written by the command line.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from rbhyst._version import __version__
from rbhyst.solve import integrators
from rbhyst.errors import AnalysisError, InputError
from rbhyst.solve.estimate import REFERENCE_RTOL, Estimator, relative_errors  # noqa: F401 (re-exported)
from rbhyst.solve.integrators import reference
from rbhyst.model.system import System
from rbhyst.solve.result import Result
from rbhyst.solve.plan import Settings, grid, simulate

COORDINATES = ("u1", "u2", "theta3")
#: a body in space
SPACE_COORDINATES = ("u1", "u2", "u3", "theta1", "theta2", "theta3")


def csv_columns(coordinates: tuple[str, ...] = COORDINATES) -> tuple[str, ...]:
    """study.csv's columns: an error column per coordinate of the body."""
    return ("integrator", "dt_s", "steps", "wall_s", *(f"err_{c}" for c in coordinates), "err_max",
            "est_max", "est_over_true")


CSV_COLUMNS = csv_columns()
#: default ladder: these multiples of the deck's dt
LADDER = (4.0, 2.0, 1.0, 0.5, 0.25, 0.125)
#: the asymptotic range of an order fit: errors below this (above it a method is still
#: finding its feet) ...
ASYMPTOTIC_MAX = 0.1
#: ... and above this many times the reference's rtol (below, the reference's own error shows)
REFERENCE_FLOOR = 1e3
#: runs shorter than this are repeated (up to REPEAT times) and the best time is kept
REPEAT_BELOW_S = 0.5
REPEAT = 3

Progress = Callable[[str, int, int], None]


@dataclass
class Run:
    """One integrator at one dt."""

    integrator: str
    dt: float
    steps: int = 0
    wall_s: float = math.nan
    errors: tuple[float, ...] = (math.nan, math.nan, math.nan)  # per coordinate (Study.coordinates)
    failed: str | None = None  # the analysis error, if it stopped
    substeps: int = 0  # extra substeps the stiffness monitor asked for
    max_substep_level: int = 0
    k0_substep_level: int = 0
    energy_balance: float = math.nan
    #: the error estimate every run makes (rbhyst.solve.estimate), max over the coordinates
    est_max: float = math.nan

    @property
    def err_max(self) -> float:
        e = [x for x in self.errors if not math.isnan(x)]
        return max(e) if e else math.nan

    @property
    def est_over_true(self) -> float:
        return self.est_max / self.err_max if self.err_max > 0 else math.nan

    def row(self) -> list:
        return [self.integrator, self.dt, self.steps, self.wall_s, *self.errors, self.err_max, self.est_max,
                self.est_over_true]


@dataclass
class Study:
    title: str
    duration: float
    deck_dt: float
    runs: list[Run]
    orders: dict
    reference: dict
    integrators: list[str] = field(default_factory=list)
    dts: list[float] = field(default_factory=list)
    #: the body's coordinates, in the order of each run's errors
    coordinates: tuple[str, ...] = COORDINATES

    def by_integrator(self) -> dict[str, list[Run]]:
        out: dict[str, list[Run]] = {}
        for r in self.runs:
            out.setdefault(r.integrator, []).append(r)
        return out

    def summary(self) -> dict:
        return {
            "rbhyst_version": __version__,
            "title": self.title,
            "duration_s": self.duration,
            "deck_dt_s": self.deck_dt,
            "integrators": self.integrators,
            "dt_s": self.dts,
            "error": "relative max-norm per coordinate: max_t |q - q_ref| / max_t |q_ref| on the run's own "
                     f"time grid t_n = n dt; err_max is the largest of {', '.join(self.coordinates)}",
            "estimate": "est_max: the error estimate an ordinary run reports (rbhyst.solve.estimate: against the adaptive "
                        f"solution at rtol {REFERENCE_RTOL:g}); est_over_true shows its honesty",
            "wall_s": "time stepping only (compiled kernel loaded beforehand), best of up to "
                      f"{REPEAT} runs for runs under {REPEAT_BELOW_S} s",
            "observed_order": self.orders,
            "reference": self.reference,
            "runs": [
                {"integrator": r.integrator, "dt_s": r.dt, "steps": r.steps, "wall_s": _num(r.wall_s),
                 **{f"err_{c}": _num(e) for c, e in zip(self.coordinates, r.errors)},
                 "err_max": _num(r.err_max), "est_max": _num(r.est_max), "est_over_true": _num(r.est_over_true),
                 "stiffness_substeps": r.substeps,
                 "max_substep_level": r.max_substep_level, "k0_substep_level": r.k0_substep_level,
                 "energy_balance": _num(r.energy_balance), "failed": r.failed}
                for r in self.runs
            ],
        }


def _num(x: float):
    return None if x is None or not math.isfinite(x) else float(x)


def default_dts(dt: float) -> list[float]:
    """A geometric ladder around the deck's dt: 4, 2, 1, 1/2, 1/4, 1/8 times it."""
    return [dt * k for k in LADDER]


def fixed_step_names() -> list[str]:
    """Every registered integrator that runs in the fixed-step loop."""
    return [n for n in integrators.names() if integrators.get(n).solve is None]


def check_integrators(names: list[str]) -> list[str]:
    known = fixed_step_names()
    problems = []
    for n in names:
        if n == reference.METHOD.name:
            problems.append("--integrators: 'reference' is what the others are measured against; it always runs once")
        elif n not in known:
            problems.append(f"--integrators: unknown {n!r}; choose from {', '.join(known)}")
    if not names:
        problems.append("--integrators: the list is empty")
    if len(set(names)) != len(names):
        problems.append("--integrators: a name is repeated")
    if problems:
        raise InputError(problems)
    return names


def check_dts(dts: list[float], duration: float) -> list[float]:
    problems = []
    for dt in dts:
        if not (math.isfinite(dt) and dt > 0):
            problems.append(f"--dt: {dt} must be a positive number of seconds")
        elif dt > duration:
            problems.append(f"--dt: {dt:g} s is longer than the analysis ({duration:g} s)")
    if not dts:
        problems.append("--dt: the list is empty")
    if problems:
        raise InputError(problems)
    return sorted(set(dts), reverse=True)


def union_grid(steps: dict[float, int]) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """All output times t = n dt of every run (merged where they coincide) and each run's indices in it."""
    grids = {dt: dt * np.arange(n + 1) for dt, n in steps.items()}
    allt = np.sort(np.concatenate(list(grids.values())))
    tol = 1e-9 * min(steps)
    keep = np.concatenate([[True], np.diff(allt) > tol])
    times = allt[keep]
    index = {}
    for dt, g in grids.items():
        i = np.clip(np.searchsorted(times, g - tol), 0, len(times) - 1)
        assert np.all(np.abs(times[i] - g) <= tol), "grid lookup"
        index[dt] = i
    return times, index


def observed_order(runs: list[Run], floor: float) -> dict:
    """Slope of log err_max against log dt over the asymptotic range.

    The range: runs that finished without extra substeps (their step is the nominal dt),
    with errors below ASYMPTOTIC_MAX and above ``floor`` (the reference's own error).
    """
    ok = sorted((r for r in runs if r.failed is None and math.isfinite(r.err_max)), key=lambda r: r.dt)
    fit = [r for r in ok if r.substeps == 0 and floor < r.err_max < ASYMPTOTIC_MAX]
    local = [
        {"dt_s": [a.dt, b.dt], "slope": math.log(b.err_max / a.err_max) / math.log(b.dt / a.dt)}
        for a, b in zip(ok, ok[1:]) if a.err_max > 0 and b.err_max > 0
    ]
    out = {"fit_dt_s": [r.dt for r in fit], "local_slopes": local}
    if len(fit) >= 2:
        x = np.log([r.dt for r in fit])
        y = np.log([r.err_max for r in fit])
        out["order"] = float(np.polyfit(x, y, 1)[0])
    else:
        out["order"] = None
        out["note"] = "fewer than two runs in the asymptotic range: widen --dt"
    return out


def _timed(system: System, settings: Settings, repeat: int) -> Result:
    res = simulate(system, settings)
    best = res.wall_s
    n = 1
    while best < REPEAT_BELOW_S and n < repeat:
        best = min(best, simulate(system, settings).wall_s)
        n += 1
    res.stats.wall_s = best
    return res


def run_study(system: System, settings: Settings, names: list[str] | None = None,
              dts: list[float] | None = None, progress: Progress | None = None,
              rtol: float = reference.RTOL, repeat: int = REPEAT) -> Study:
    """Each integrator at each dt against one reference run; see the module docstring.

    ``repeat``: runs shorter than REPEAT_BELOW_S are timed up to this many times (best kept).
    """
    from rbhyst.solve.static import at_rest_under_gravity

    # every solution starts at rest at the static equilibrium under gravity, as a run does (the
    # runs find it themselves; the reference and the estimate's solution are given it here)
    system = at_rest_under_gravity(system)
    names = check_integrators(list(names) if names is not None else fixed_step_names())
    duration = settings.duration if settings.duration is not None else system.excitation.duration
    if duration is None:
        raise InputError("analysis.duration: required when no record or finite pulse gives it")
    dts = check_dts(list(dts) if dts is not None else default_dts(settings.dt), duration)
    base = dataclasses.replace(settings, every=1, points=(), spectra=None)  # (they would only cost time)
    steps = {dt: grid(system, dataclasses.replace(base, dt=dt))[0] for dt in dts}
    times, index = union_grid(steps)
    total = 1 + len(names) * len(dts)
    done = 0

    def tick(label: str) -> None:
        if progress is not None:
            progress(label, done, total)

    tick(f"reference (rtol {rtol:g})")
    ref_settings = dataclasses.replace(base, integrator="reference")
    ref, ref_stats = reference.solve_with_stats(system, ref_settings, rtol=rtol, t_out=times)
    for _ in range(repeat - 1):  # timed like the others: best of a few
        if ref_stats["wall_s"] >= REPEAT_BELOW_S:
            break
        again = reference.solve_with_stats(system, ref_settings, rtol=rtol, t_out=times)[1]
        ref_stats["wall_s"] = min(ref_stats["wall_s"], again["wall_s"])
    done += 1
    tick(f"estimate's adaptive solution (rtol {REFERENCE_RTOL:g})")
    estimate_q = Estimator(system, times).solution(REFERENCE_RTOL).q
    # the adaptive solution's q is the kernels': turned to the deck's axes and measured from the
    # static equilibrium, as a run's table (and the reference's) gives it
    estimate_q = system.to_deck(estimate_q - (system.static.q if system.static is not None else 0.0))
    coordinates = tuple(c.key("d") for c in system.coordinates)
    runs = []
    for name in names:
        for dt in dts:
            tick(f"{name}, dt = {dt:g} s")
            run = Run(name, dt, steps=steps[dt], errors=(math.nan,) * len(coordinates))
            try:
                res = _timed(system, dataclasses.replace(base, integrator=name, dt=dt), repeat)
            except AnalysisError as err:
                run.failed = str(err)
            else:
                n = min(len(res.d), len(index[dt]))
                run.errors = relative_errors(res.d[:n], ref.d[index[dt][:n]], system)
                run.est_max = max(relative_errors(res.d[:n], estimate_q[index[dt][:n]], system))
                run.wall_s = res.wall_s
                run.substeps = res.substeps
                run.max_substep_level = res.max_substep_level
                run.k0_substep_level = res.min_substep_level
                run.energy_balance = res.energy_balance
            runs.append(run)
            done += 1
    tick("done")
    floor = REFERENCE_FLOOR * rtol
    orders = {}
    for name in names:
        o = observed_order([r for r in runs if r.integrator == name], floor)
        o["expected"] = integrators.get(name).order
        orders[name] = o
    ref_stats = dict(ref_stats, name="reference", order_fit_floor=floor)
    return Study(title=system.title, duration=duration, deck_dt=settings.dt, runs=runs, orders=orders,
                 reference=ref_stats, integrators=names, dts=dts, coordinates=coordinates)


def write_csv(study: Study, path: Path) -> None:
    lines = [",".join(csv_columns(study.coordinates))]
    for r in study.runs:
        vals = r.row()
        cells = [vals[0], f"{vals[1]:.10g}", str(vals[2])]
        cells += ["" if not math.isfinite(x) else f"{x:.6g}" for x in vals[3:]]
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def write_json(study: Study, path: Path) -> None:
    path.write_text(json.dumps(study.summary(), indent=2) + "\n")
