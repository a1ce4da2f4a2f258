"""How accurate a run is, and runs that meet an accuracy asked for.

The error of a history is measured as ``study`` measures it: max_t |q - q_exact| / max_t
|q_exact| per coordinate u1, u2, theta3. It is estimated against the event-located adaptive
integration (rbhyst.integrators.reference): between reversals the equation of motion is
smooth, every reversal is located as an event and the load is fitted exactly, so its only
error is the Runge-Kutta pair's, controlled by rtol. Two solutions, at REFERENCE_RTOL and
100 times looser, say how well the scene's history is determined at all:

- their difference (the *spread*) falls about a hundredfold per hundredfold of rtol on an
  ordinary scene (1e-5 to 1e-8 on the sample decks), and the run's error is then its distance
  from the tighter one: honest in both directions, since that solution is some thousand times
  more accurate than any run worth reporting;
- on a sensitive scene (sharp yield driven near a bifurcation, rotations that decide which
  elements yield) the two differ by as much as the run itself: no step size determines the
  history, and the estimate says so (status "sensitive") with the spread of the peaks, which
  may still be stable.

Fixed-step methods win on cost where reversals are many (each is an adaptive step); past a
budget of adaptive steps the estimate falls back to halving the run's step (status
"step-halving"), which assumes the method's order and is less trustworthy on hysteretic
scenes, and says so.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from .errors import AnalysisError
from .model import System

#: the estimator's adaptive solution, and the check of how well it is determined (x 100 looser)
REFERENCE_RTOL = 1e-9
CHECK_FACTOR = 100.0
#: adaptive steps the estimate may take per step of the run before it halves the step instead
STEP_BUDGET = 400
#: tolerance mode: the adaptive rtol tried first is the tolerance times this (its error is some
#: 100-300 rtol on the sample decks and cases), then 100 times tighter until met or RTOL_MIN
RTOL_PER_TOL = 1e-3
RTOL_MIN = 1e-13
COORDINATES = ("u1", "u2", "theta3")


def relative_errors(d: np.ndarray, d_ref: np.ndarray, system: System) -> tuple[float, float, float]:
    """max_t |q - q_ref| / max_t |q_ref| per coordinate.

    A coordinate the reference leaves at rest (below 1e-12 of the body's motion, e.g. the
    rotation of a symmetric scene) is measured against the body's motion instead: the
    largest translation, or the largest rotation times the radius of gyration.
    """
    diff = np.max(np.abs(d - d_ref), axis=0)
    peak = np.max(np.abs(d_ref), axis=0)
    rg = math.sqrt(system.mass[2] / system.mass[0])
    body = max(peak[0], peak[1], peak[2] * rg)
    scale = np.array([body, body, body / rg])
    peak = np.where(peak > 1e-12 * scale, peak, scale)
    with np.errstate(invalid="ignore", divide="ignore"):
        err = np.where(peak > 0, diff / peak, np.where(diff > 0, np.inf, 0.0))
    return tuple(float(x) for x in err)


def _peak_spread(*histories: np.ndarray) -> dict[str, float]:
    """The largest relative difference between the peaks |q| of several histories, per coordinate."""
    peaks = np.array([np.max(np.abs(h), axis=0) for h in histories])
    top = np.max(peaks, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = np.where(top > 0, (np.max(peaks, axis=0) - np.min(peaks, axis=0)) / top, 0.0)
    return dict(zip(COORDINATES, map(float, spread)))


class Estimator:
    """Adaptive solutions of one scene on one grid of times, computed once and reused (a study
    compares many runs with the same ones)."""

    def __init__(self, system: System, t: np.ndarray, max_steps: int | None = None):
        from .integrators import reference

        self.system = system
        self.t = np.asarray(t, dtype=float)
        self.max_steps = max_steps if max_steps is not None else reference.MAX_STEPS
        self._pieces = None
        self._solutions: dict[float, object] = {}
        self.wall_s = 0.0

    def solution(self, rtol: float):
        from .integrators import reference

        if rtol not in self._solutions:
            tic = time.perf_counter()
            if self._pieces is None:
                self._pieces = reference.load_pieces(self.system, float(self.t[-1]))
            try:
                self._solutions[rtol] = reference.integrate(self.system, self.t, rtol, pieces=self._pieces,
                                                            max_steps=self.max_steps)
            finally:
                self.wall_s += time.perf_counter() - tic
        return self._solutions[rtol]

    def assess(self, q: np.ndarray, rtol: float = REFERENCE_RTOL, check: float | None = None) -> dict:
        """The error of q (at self.t) against the solution at rtol; how determined that one is
        against the one at ``check`` (default rtol x CHECK_FACTOR)."""
        check = check if check is not None else rtol * CHECK_FACTOR
        tight = self.solution(rtol)
        loose = self.solution(check)
        err = relative_errors(q, tight.q, self.system)
        spread = relative_errors(loose.q, tight.q, self.system)
        return {
            "estimated_error": dict(zip(COORDINATES, err)),
            "reference_spread": dict(zip(COORDINATES, spread)),
            "peaks_spread": _peak_spread(q, tight.q, loose.q),
            "reference": {"rtol": float(f"{rtol:.6g}"), "check_rtol": float(f"{check:.6g}"), "steps": tight.stats["steps"],
                          "reversals": tight.stats["reversals"]},
        }


def estimate(result, settings) -> dict:
    """summary.json's ``accuracy`` for a finished run (see the module docstring)."""
    system = result.system
    q = result.q_sample
    t, q = q[:, 0], q[:, 1:4]
    tic = time.perf_counter()
    budget = STEP_BUDGET * max(result.stats.steps, 1)
    est = Estimator(system, t, max_steps=budget)
    adaptive = result.solver is not None
    try:
        if adaptive:
            # the run is itself the adaptive solution at settings.rtol: against one 100 times tighter
            rtol = result.solver["rtol"]
            out = est.assess(q, rtol=rtol / CHECK_FACTOR, check=rtol)
            out["method"] = (f"against the event-located adaptive solution at rtol {rtol / CHECK_FACTOR:g} "
                             "(100 times tighter than the run's)")
        else:
            out = est.assess(q)
            out["method"] = (f"against the event-located adaptive solution (DOP853, every reversal an event) at "
                             f"rtol {REFERENCE_RTOL:g}, itself checked against rtol {REFERENCE_RTOL * CHECK_FACTOR:g}")
    except AnalysisError as err:
        from .integrators.reference import TooManySteps

        if adaptive or not isinstance(err, TooManySteps):
            return {"estimated_error": None, "tolerance": settings.tolerance, "status": "unavailable",
                    "method": f"the adaptive solution failed: {err}", "wall_s": time.perf_counter() - tic}
        out = _halving(result, settings)
        out["why"] = f"the adaptive solution needs more than {budget} steps ({STEP_BUDGET} per step of the run)"
    spread = max(out.get("reference_spread", {}).values(), default=0.0)
    worst = max(out["estimated_error"].values())
    if "status" not in out:
        out["status"] = "sensitive" if spread > settings.warn_error else "estimated"
        if out["status"] == "estimated" and spread > worst:
            # the run cannot be measured closer than the reference is determined
            out["estimated_error"] = {k: max(v, out["reference_spread"][k]) for k, v in out["estimated_error"].items()}
    out["tolerance"] = settings.tolerance
    out["compared_steps"] = int(len(t))
    out["compared_every"] = int(result.stats.steps // max(len(t) - 1, 1)) if len(t) > 1 else 1
    out["wall_s"] = time.perf_counter() - tic
    return out


def _halving(result, settings) -> dict:
    """The run again at dt/2: error ~ |q_h - q_h/2| 2^p / (2^p - 1) with the method's order p."""
    from . import integrators
    from .simulate import prepare

    order = integrators.get(settings.integrator).order
    half = prepare(result.system, dataclasses.replace(settings, dt=settings.dt / 2, every=1)).run(keep=False)
    t = result.q_sample[:, 0]
    th = half.q_sample
    qh = np.column_stack([np.interp(t, th[:, 0], th[:, k]) for k in (1, 2, 3)])
    diff = relative_errors(result.q_sample[:, 1:4], qh, result.system)
    factor = 2.0**order / (2.0**order - 1.0)
    return {"estimated_error": dict(zip(COORDINATES, (factor * d for d in diff))), "status": "step-halving",
            "method": f"step halving: |q(dt) - q(dt/2)| x 2^p/(2^p - 1), p = {order} (convergence on hysteretic "
                      "scenes is irregular: this can be optimistic)"}


def warnings_for(accuracy: dict, settings) -> list[str]:
    """The warnings an estimate calls for, with what would do."""
    if accuracy is None:
        return []
    if accuracy["status"] == "unavailable":
        return [f"the error could not be estimated: {accuracy['method']}"]
    err = accuracy["estimated_error"]
    name, worst = max(err.items(), key=lambda kv: kv[1])
    out = []
    if accuracy["status"] == "sensitive":
        spread = max(accuracy["reference_spread"].values())
        peaks = max(accuracy["peaks_spread"].values())
        out.append(f"the history is sensitive: adaptive solutions at rtol {accuracy['reference']['check_rtol']:g} "
                   f"and {accuracy['reference']['rtol']:g} differ by {spread:.1%}, so no step size determines it to "
                   f"{settings.warn_error:.0%}; report the peaks (they differ by {peaks:.1%} between the run and "
                   "both), not the history")
    elif worst > settings.warn_error:
        hint = ""
        if settings.integrator != "adaptive":
            dt = settings.dt * 0.7 * (settings.warn_error / worst) ** 0.5
            hint = f"; dt = {dt:.3g} s, --integrator adaptive, or --tolerance {settings.warn_error:g} would do"
        else:
            hint = f"; --tolerance {settings.warn_error:g} would do"
        out.append(f"estimated error {worst:.2%} in {name} exceeds analysis.warn_error = {settings.warn_error:.0%}{hint}")
    return out


def meet_tolerance(system: System, settings, keep: bool = True, csv_path=None):
    """The run whose estimated error (largest coordinate) is at most settings.tolerance.

    The adaptive integration first, at rtol = tolerance x RTOL_PER_TOL, then 100 times tighter
    while the estimate exceeds the tolerance (each attempt's check is the next's answer, computed
    once); where reversals are so many that it exceeds its step budget, the deck's fixed-step
    method at dt, dt/2, dt/4 ... with step-halving estimates. The output stays on the deck's dt.
    An AnalysisError (exit 3) says what was reached where neither meets it.
    """
    from .integrators.reference import TooManySteps
    from .simulate import output_steps, prepare

    tol = settings.tolerance
    n_steps = output_steps(system, settings)
    t = settings.dt * np.arange(n_steps + 1)
    est = Estimator(system, t[:: max(1, -(-(n_steps + 1) // 200_000))], max_steps=STEP_BUDGET * max(n_steps, 1))
    rtol = min(1e-6, max(RTOL_MIN, tol * RTOL_PER_TOL))
    reached = None
    tic = time.perf_counter()
    try:
        while rtol >= RTOL_MIN:
            s = dataclasses.replace(settings, integrator="adaptive", rtol=rtol)
            q = est.solution(rtol).q
            acc = est.assess(q, rtol=rtol / CHECK_FACTOR, check=rtol)
            worst = max(acc["estimated_error"].values())
            spread_peaks = max(acc["peaks_spread"].values())
            reached = (worst, rtol)
            if worst <= tol:
                result = prepare(system, s).run(keep=keep, csv_path=csv_path)
                acc.update(status="estimated", tolerance=tol, wall_s=est.wall_s,
                           method=f"tolerance {tol:g}: the adaptive integration at rtol {rtol:g}, measured against "
                                  f"rtol {rtol / CHECK_FACTOR:g}", compared_steps=int(len(est.t)))
                result.accuracy = acc
                return result
            rtol /= CHECK_FACTOR
    except TooManySteps:
        return _ladder(system, settings, keep, csv_path, tic)
    worst, rtol = reached
    raise AnalysisError(
        f"tolerance {tol:g} not met: the adaptive integration reached {worst:.3g} at rtol {rtol:g} and does not "
        f"converge further (peaks differ by {spread_peaks:.2%}): the scene's history is sensitive to round-off; "
        f"a tolerance above {worst:.2g} can be met, or report the peaks")


#: the fixed-step ladder of tolerance mode halves dt at most this many times
LADDER_HALVINGS = 8


def _ladder(system: System, settings, keep, csv_path, tic):
    from .simulate import prepare

    tol = settings.tolerance
    worst = math.inf
    for k in range(LADDER_HALVINGS + 1):
        s = dataclasses.replace(settings, dt=settings.dt / 2**k, every=settings.every * 2**k)
        result = prepare(system, s).run(keep=keep, csv_path=csv_path)
        acc = _halving(result, s)
        worst = max(acc["estimated_error"].values())
        if worst <= tol:
            acc.update(tolerance=tol, wall_s=time.perf_counter() - tic,
                       why="the adaptive integration exceeds its step budget on this scene (many reversals)",
                       compared_steps=int(len(result.q_sample)))
            result.accuracy = acc
            return result
    raise AnalysisError(f"tolerance {tol:g} not met: {settings.integrator} at dt = {settings.dt / 2**LADDER_HALVINGS:.3g} s "
                        f"reached {worst:.3g} (the adaptive integration exceeds its step budget here); "
                        "ask for a looser tolerance or a smaller analysis.dt")
