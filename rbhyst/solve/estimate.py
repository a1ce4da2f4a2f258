"""How accurate a run is, and runs that meet an accuracy asked for.

The error of a history is measured as ``study`` measures it, max_t |x - x_exact| / max_t
|x_exact|, for every output an engineer reads: u1, u2, theta3, the total accelerations, the
mounts' resultant, each element's force, each point's motion (history.estimate_columns), and
the body's response spectra (their largest difference over periods and dampings). It is
estimated against the event-located adaptive integration (rbhyst.solve.integrators.reference):
between reversals the equation of motion is smooth, every reversal is located as an event and
the load is followed exactly, so its only error is the Runge-Kutta pair's, controlled by rtol;
its accelerations come from the same equation of motion as the run's (history.Layout). The run
is measured against one solution at REFERENCE_RTOL, some thousand times more accurate than any
run worth reporting, so the distance to it is the run's error, honest in both directions.

Where that error is near or above the warning (CHECK_ABOVE x warn_error), a second solution 100
times looser says whether the history is determined at all:

- their difference (the *spread*) falls about a hundredfold per hundredfold of rtol on an
  ordinary scene (1e-5 to 1e-8 on the sample decks): the error is the step's, and a smaller dt
  would do;
- on a sensitive scene (sharp yield driven near a bifurcation, rotations that decide which
  elements yield) the two differ by as much as the run itself: no step size determines the
  history, and the estimate says so (status "sensitive") with the spread of the peaks, which
  may still be stable.

Below it the check is not computed: the run itself is a perturbed solution, its local errors
thousands of times the reference's, and it agrees with the reference to its estimate; a history
that perturbations of that size leave determined to better than the warning needs no second
solution to say so. An adaptive run is its own check (the solution 100 times looser than the
reference at the same times), so it costs one solution too.

A fixed-step run of chang, central difference or Newmark is measured against its companion
instead (rbhyst.solve.companion: the same method with its leading local error taken out of the
load, one more time stepping), no adaptive solution at all. Near the warning its check is the
run again with COMPANION_PROBE of the companion's source added: a determined history moves by
that fraction of its error, a sensitive one as much as the run; where it moves by more than the
warning, and where the companion does not apply or its estimate exceeds COMPANION_LARGEST, the
adaptive solutions as above.

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

from rbhyst.errors import AnalysisError
from rbhyst.solve.history import estimate_columns, largest_abs
from rbhyst.solve.scales import AT_REST, family_scales, to_length as _to_length  # noqa: F401
from rbhyst.model.system import System
from rbhyst.solve.static import at_rest_under_gravity

#: the estimator's adaptive solution, and the check of how well it is determined (x 100 looser)
REFERENCE_RTOL = 1e-9
CHECK_FACTOR = 100.0
#: a fixed-step run is checked (the second solution) only where its largest estimate exceeds this
#: fraction of analysis.warn_error: below it, the run itself, whose local errors are thousands of
#: times the reference's, has shown the history determined to its own error
CHECK_ABOVE = 0.5
#: adaptive steps the estimate may take per step of the run before it halves the step instead
STEP_BUDGET = 400
#: tolerance mode: the adaptive rtol tried first is the tolerance times this (its error is some
#: 100-300 rtol on the sample decks and cases), then 100 times tighter until met or RTOL_MIN
RTOL_PER_TOL = 1e-3
RTOL_MIN = 1e-13
#: a column whose peak stays below this fraction of its family's scale is small against the motion
#: that matters (the torsion a symmetric body's rocking couples in with exact rotations, a cross
#: acceleration): its error is stated against this fraction of the scale, so that a tiny
#: quantity's large relative error is reported as what it is worth, and a small column that is
#: badly wrong still is (50 % of a column at 0.1 % of the scale reads 5 %)
NEGLIGIBLE = 0.01
#: the spectra's error is estimated on runs of at most this many compute steps (the reference
#: is then computed at each of them, as the run's spectra were driven)
SPECTRA_ROWS = 500_000
#: rows of the adaptive solution's table made at a time for the columns compared
VALUES_BLOCK = 16_384
#: a warning names at most this many quantities beside the worst (then "and k more")
WARN_NAMES = 8


def relative_errors(d: np.ndarray, d_ref: np.ndarray, system: System) -> tuple[float, ...]:
    """max_t |q - q_ref| / max_t |q_ref| per coordinate (u1, u2, theta3: ``study``'s measure)."""
    keys = [c.key("d") for c in system.coordinates]
    return tuple(float(x) for x in column_errors(d, d_ref, keys, ["d"] * len(keys), system))


def column_errors(values: np.ndarray, ref: np.ndarray, keys, families, system: System) -> np.ndarray:
    """max_t |x - x_ref| / max_t |x_ref| for every column.

    A column the reference leaves at rest (below AT_REST of its family: the rotation of a
    symmetric scene, the cross acceleration of a symmetric body) is measured against its
    family's scale instead: the largest of the family's peaks, a rotation counted at the
    radius of gyration, a moment over it; a column below NEGLIGIBLE of that scale against
    NEGLIGIBLE x the scale.
    """
    return relative_to_peaks(largest_abs(values - ref), largest_abs(ref), keys, families, system)


def relative_to_peaks(diff: np.ndarray, peak: np.ndarray, keys, families, system: System) -> np.ndarray:
    """column_errors from each column's largest difference and the reference's peak."""
    return scaled_errors(diff, error_scales(peak, keys, families, system))


def scaled_errors(diff: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """Each column's largest difference over its error_scales: inf where the scale is 0 and the
    difference is not, 0 where both are."""
    out = np.where(diff > 0, np.inf, 0.0)  # (where the scale is 0: no division, no warning to silence)
    return np.divide(diff, scales, out=out, where=scales > 0)


def error_scales(peak: np.ndarray, keys, families, system: System) -> np.ndarray:
    """What column_errors divides each column's largest difference by, from the reference's
    peaks: the peak, or the family's scale where the column is at rest, NEGLIGIBLE x the scale
    where it is below that."""
    scale = family_scales(peak, keys, families, system)
    return np.where(peak > AT_REST * scale, np.maximum(peak, NEGLIGIBLE * scale), scale)


def _peak_spread(keys, *histories: np.ndarray) -> dict[str, float]:
    """The largest relative difference between the peaks |x| of several histories, per column."""
    peaks = np.array([np.max(np.abs(h), axis=0) for h in histories])
    top = np.max(peaks, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = np.where(top > 0, (np.max(peaks, axis=0) - np.min(peaks, axis=0)) / top, 0.0)
    return dict(zip(keys, map(float, spread)))


class Estimator:
    """Adaptive solutions of one scene at one set of times, computed once and reused (a study
    compares many runs with the same ones), and the columns of a run's table they give
    (history.estimate_columns of ``layout``)."""

    def __init__(self, system: System, t: np.ndarray, max_steps: int | None = None, layout=None,
                 t_end: float | None = None):
        """t: the times compared (from 0); t_end: the end of the analysis, if later."""
        from rbhyst.solve.integrators import reference

        self.system = system
        self.t = np.asarray(t, dtype=float)
        self.t_end = max(float(self.t[-1]), t_end or 0.0)
        self.max_steps = max_steps if max_steps is not None else reference.MAX_STEPS
        self.layout = layout
        self._pieces = None
        self._solutions: dict[tuple[float, int], object] = {}
        self._values: dict[tuple[float, int], np.ndarray] = {}  # (the columns compared, at self.t)
        self._stats: dict[tuple[float, int], dict] = {}
        self._columns = None
        self.wall_s = 0.0

    def solution(self, rtol: float, t: np.ndarray | None = None):
        """The adaptive solution at ``rtol``, at self.t (or the times t, from 0)."""
        from rbhyst.solve.integrators import reference

        times = self.t if t is None else t
        key = (rtol, len(times), float(times[-1]))
        if key not in self._solutions:
            tic = time.perf_counter()
            if self._pieces is None:
                self._pieces = reference.load_pieces(self.system, self.t_end)
            try:
                self._solutions[key] = reference.integrate(self.system, times, rtol, pieces=self._pieces,
                                                           max_steps=self.max_steps)
            finally:
                self.wall_s += time.perf_counter() - tic
        return self._solutions[key]

    @property
    def columns(self) -> list[tuple[str, int, str]]:
        if self._columns is None:
            self._columns = estimate_columns(self.layout)
        return self._columns

    def values(self, rtol: float) -> np.ndarray:
        """(len(self.t), k) the estimate's columns of the adaptive solution at ``rtol``: integrated
        a block of rows at a time and only those columns kept, unless the solution is at hand."""
        from rbhyst.solve.integrators import reference

        key = (rtol, len(self.t), float(self.t[-1]))
        if key not in self._values:
            cols = [c for _, c, _ in self.columns]
            n = len(self.t)
            out = np.empty((n, len(cols)))
            whole = self._solutions.get(key)
            tic = time.perf_counter()
            try:
                if whole is None:
                    if self._pieces is None:
                        self._pieces = reference.load_pieces(self.system, self.t_end)
                    run = reference.Integration(self.system, n, lambda lo, hi: self.t[lo:hi], rtol, pieces=self._pieces,
                                                max_steps=self.max_steps, window=VALUES_BLOCK, t_end=float(self.t[-1]))
                    block = lambda lo, hi: run.take(hi).raw(self.system)  # noqa: E731
                else:
                    raw = whole.raw(self.system)
                    block = lambda lo, hi: raw.slice(lo, hi)  # noqa: E731
                for lo in range(0, n, VALUES_BLOCK):
                    hi = min(n, lo + VALUES_BLOCK)
                    out[lo:hi] = self.layout.table(block(lo, hi))[:, cols]
            finally:
                self.wall_s += time.perf_counter() - tic
            self._stats[key] = whole.stats if whole is not None else run.stats()
            self._values[key] = out
        return self._values[key]

    def stats(self, rtol: float) -> dict:
        """What the adaptive solution at ``rtol`` at self.t took (reference.Integration.stats)."""
        key = (rtol, len(self.t), float(self.t[-1]))
        return self._stats[key] if key in self._stats else self.solution(rtol).stats

    def assess(self, values: np.ndarray, rtol: float = REFERENCE_RTOL, check: float | None = None,
               loose: np.ndarray | None = None) -> dict:
        """The error of ``values`` (the estimate's columns at self.t) against the solution at
        rtol; with ``check`` (an rtol), how determined that one is against the solution there
        (``loose``: its columns, where they are at hand: an adaptive run is its own check)."""
        keys = [k for k, _, _ in self.columns]
        tight = self.values(rtol)
        err = column_errors(values, tight, keys, self.families, self.system)
        stats = self.stats(rtol)
        out = {"estimated_error": dict(zip(keys, map(float, err))),
               "reference": {"rtol": float(f"{rtol:.6g}"), "steps": stats["steps"],
                             "reversals": stats["reversals"]}}
        if check is not None:
            self.add_check(out, values, rtol, check, loose)
        return out

    def add_check(self, out: dict, values: np.ndarray, rtol: float, check: float,
                  loose: np.ndarray | None = None) -> None:
        """The spread of the solutions at rtol and ``check`` into ``out`` (see assess)."""
        keys = [k for k, _, _ in self.columns]
        tight = self.values(rtol)
        loose = self.values(check) if loose is None else loose
        spread = column_errors(loose, tight, keys, self.families, self.system)
        out["reference_spread"] = dict(zip(keys, map(float, spread)))
        out["peaks_spread"] = _peak_spread(keys, values, tight, loose)
        out["reference"]["check_rtol"] = float(f"{check:.6g}")

    @property
    def families(self) -> list[str]:
        return [f for _, _, f in self.columns]


def estimate(result, settings, companion=None, spare_core: bool = False, screen: bool = False) -> dict:
    """summary.json's ``accuracy`` for a finished run (see the module docstring). ``companion``:
    (the run's plan, the RunTap that saw its chunks), where rbhyst.solve.companion applies;
    ``spare_core``: a core is free for the companion's check while the companion runs (not in
    a sweep's worker, whose siblings take every core). ``screen``: a pass that is run again at a
    finer step where it exceeds warn_error (rbhyst.solve.choose): above warn_error the estimate
    stops at the companion's number (status "screened": no check of how determined the history
    is, no adaptive solution where the companion's is large), which predicts the step."""
    system = result.system
    t, values = result.compared[:, 0], result.compared[:, 1:]
    tic = time.perf_counter()
    if companion is not None:
        out = _from_companion(result, settings, *companion, spare_core=spare_core, screen=screen)
        if out is not None:
            _settle_status(out, settings)
            out.update(tolerance=settings.tolerance, compared_steps=int(len(t)),
                       compared_every=int(result.compare_every),
                       wall_s=time.perf_counter() - tic + companion[1].wall_s)
            return out
    budget = STEP_BUDGET * max(result.stats.steps, 1)
    est = Estimator(system, t, max_steps=budget, layout=result.layout, t_end=result.stats.steps * settings.dt)
    adaptive = result.solver is not None
    rtol = result.solver["rtol"] / CHECK_FACTOR if adaptive else REFERENCE_RTOL
    try:
        if adaptive:
            # the run is itself the adaptive solution at settings.rtol: against one 100 times tighter,
            # and its own check (the same steps at the same times: no second integration)
            out = est.assess(values, rtol=rtol, check=result.solver["rtol"], loose=values)
            out["method"] = (f"against the event-located adaptive solution at rtol {rtol:g} "
                             "(100 times tighter than the run's)")
        else:
            out = est.assess(values)
            out["method"] = (f"against the event-located adaptive solution (DOP853, every reversal an event) at "
                             f"rtol {REFERENCE_RTOL:g}")
            worst = max(out["estimated_error"].values())
            if screen and worst > settings.warn_error:
                out["status"] = "screened"  # (to be run again at a finer step: its check would be wasted)
            elif worst > CHECK_ABOVE * settings.warn_error:
                # an error near or above the warning: is it the step's (a smaller dt would do) or is
                # the history itself undetermined? The solution 100 times looser says
                est.add_check(out, values, rtol, rtol * CHECK_FACTOR)
                out["method"] += f", itself checked against rtol {rtol * CHECK_FACTOR:g}"
    except AnalysisError as err:
        from rbhyst.solve.integrators.reference import TooManySteps

        if adaptive or not isinstance(err, TooManySteps):
            return {"estimated_error": None, "tolerance": settings.tolerance, "status": "unavailable",
                    "method": f"the adaptive solution failed: {err}", "wall_s": time.perf_counter() - tic}
        out = _halving(result, settings)
        out["why"] = f"the adaptive solution needs more than {budget} steps ({STEP_BUDGET} per step of the run)"
    else:
        _add_spectra_errors(out, result, est, rtol)
    _settle_status(out, settings)
    out["tolerance"] = settings.tolerance
    out["compared_steps"] = int(len(t))
    out["compared_every"] = int(result.compare_every)
    out["wall_s"] = time.perf_counter() - tic
    return out


#: the companion's check of a run near or above the warning: the run again with this fraction of
#: the companion's source added. On the sample decks and the cases of 0.1 it moves by 7e-4 - 6e-3
#: of the error where the history is determined (the adaptive solutions converge), by 80 % to
#: 100 % where it is not (silent-70, -149, -476, -782)
COMPANION_PROBE = 1e-3
#: the companion is a perturbation of the run by its own error: past this error the two are
#: different histories (silent-25 at 39 %: a quarter of the truth; silent-222 at 250 %: twice it),
#: and the adaptive solutions give the number (up to 20 % the random scenes' largest estimates
#: are 0.8-1.7 of the truth)
COMPANION_LARGEST = 0.2
#: the modified equation is a series in omega h: beyond this the companion is not trusted
COMPANION_OMEGA_DT = 1.0
#: the check runs beside the companion (a spare core) from this many element steps of the run
#: (about 2 ms of stepping): below, a thread's start and the two threads' turns at Python's lock
#: cost more than it saves (the random scenes of the tests, 100-900 steps: their median estimate
#: 4.9 -> 6.2 times their stepping with a thread, the seed deck's 320,000: 4.0 -> 2.7)
BESIDE_MIN_WORK = 100_000


def _from_companion(result, settings, plan, tap, spare_core: bool = False, screen: bool = False) -> dict | None:
    """The estimate from the run's companion (rbhyst.solve.companion), or None where the adaptive
    solutions must say it: a step whose Newton iterations failed in the companion where the
    run's converged, an element out of its range, an estimate past COMPANION_LARGEST, a history
    the check finds undetermined. With ``spare_core`` the check (the probe) runs on a thread of
    its own beside the companion, before it is known to be needed (the kernels hold no lock of
    Python's): the seed deck's estimate 24 -> 11 ms with the rest of the companion's making; the
    check's result is dropped where it is not needed. Without, the companion, the check where
    it is needed and their reductions are one compiled call (companion.estimate_in_one_call:
    the same numbers to the bit, without some forty calls of Python around them). A long run's
    companion stepped alongside it (``tap`` an rbhyst.solve.alongside.Alongside): its changes
    are reduced already, and the check, where it is needed, is the run stepped again with the
    probe beside it (the same numbers to the bit, in a chunk's memory)."""
    from rbhyst.solve.beside import Beside
    from rbhyst.solve.companion import Companion, estimate_in_one_call

    stats = result.stats
    if stats.max_omega_dt > COMPANION_OMEGA_DT:
        return None
    cols = estimate_columns(result.layout)
    keys, families = [k for k, _, _ in cols], [f for _, _, f in cols]
    # every column against the run's peaks over every step (its extremes: the compared rows' where
    # it compares every step; the companion's are the same to within the error, a second-order
    # change of a relative error)
    extremes, columns = result.extremes, [c for _, c, _ in cols]
    peaks = np.maximum(np.abs(extremes.max[columns]), np.abs(extremes.min[columns]))
    scales = error_scales(peaks, keys, families, result.system)
    check = CHECK_ABOVE * settings.warn_error
    largest = settings.warn_error if screen else COMPANION_LARGEST  # (a screen's pass past it is run again)
    streamed = getattr(tap, "streamed", False)  # (stepped alongside the run: rbhyst.solve.alongside)
    beside = spare_core and stats.steps_taken * plan.bvec.shape[0] >= BESIDE_MIN_WORK
    if streamed:
        assert tap.compare_every == result.compare_every, "the companion compares the run's compared nodes"
        changed, wall = tap.changed()
        checked = None  # (the probe steps where it is asked for: the run again beside it)
    elif beside:
        companion = Companion(plan, tap, result.compare_every)
        change = result.layout.largest_change

        def probe():
            """How far the run moves under COMPANION_PROBE of the companion's source: every
            column's largest change (None: see Companion.probe), and the kernel seconds."""
            moved, took = companion.probe(COMPANION_PROBE)
            return (None if moved is None else change(*moved)), took

        ahead = Beside(probe, name="rbhyst companion's check")
        try:
            diff, wall = companion.run()
            changed = None if diff is None else change(*diff)
        finally:
            checked = ahead.result()  # (never left running)
    else:
        # the companion, and the probe where its estimate asks for it, in one compiled call
        changed, moved, wall = estimate_in_one_call(plan, tap, result.compare_every, result.layout, scales, check,
                                                    largest, COMPANION_PROBE)
        checked = (moved, 0.0) if moved is not None else None
    if changed is None:
        return None
    err = scaled_errors(changed, scales)
    info = {"steps": int(stats.steps_taken), "wall_s": wall}
    method = (f"against the run's companion: {settings.integrator} with its leading local error taken out of the "
              "load (the method's modified equation) and every element's reversal located within its step")
    if screen and max(err, default=0.0) > largest:
        return {"estimated_error": dict(zip(keys, map(float, err))), "companion": info, "status": "screened",
                "method": method + " (a pass to be run again at a finer step: not checked further)"}
    if max(err, default=0.0) > COMPANION_LARGEST:
        return None
    if max(err, default=0.0) > check:
        # near the warning: is the history determined? The run again, COMPANION_PROBE of the
        # companion's source added: a determined history moves by that fraction of the error, a
        # sensitive one as much as the run itself (then the adaptive solutions say how much)
        moved, took = checked if checked is not None else (None, 0.0)
        if streamed:
            moved, took = tap.probe(COMPANION_PROBE)
        if moved is None:
            return None
        spread = scaled_errors(moved, scales)
        info.update(wall_s=wall + took, probe=COMPANION_PROBE, spread=float(max(spread, default=0.0)))
        if info["spread"] > settings.warn_error:
            return None
    return {"estimated_error": dict(zip(keys, map(float, err))), "companion": info, "method": method}


def _settle_status(out: dict, settings) -> None:
    """'sensitive' where the two adaptive solutions differ by more than warn_error, else 'estimated'
    (an error never below the reference's own spread)."""
    spread = max(out.get("reference_spread", {}).values(), default=0.0)
    worst = max(out["estimated_error"].values())
    if "status" not in out:
        out["status"] = "sensitive" if spread > settings.warn_error else "estimated"
        if out["status"] == "estimated" and spread > worst:
            # the run cannot be measured closer than the reference is determined
            out["estimated_error"] = {k: max(v, out["reference_spread"].get(k, 0.0))
                                      for k, v in out["estimated_error"].items()}


def _add_spectra_errors(out: dict, result, est: Estimator, rtol: float) -> None:
    """The error of every spectrum of the body (G and the points; the ground's comes from its
    signal, not from the integration), as the largest difference of sa from the reference's
    spectrum over periods and dampings, relative to the reference's peak: ``sa_<location>_<direction>``."""
    if result.spectra is None:
        return
    from rbhyst.solve.plan import body_sink, compute_times, splitting

    s = result.settings
    bounds, substeps = splitting(result.system, s, result.stats.steps)
    times = np.concatenate([[0.0], compute_times(bounds, substeps, s.dt)])
    if len(times) > SPECTRA_ROWS:
        out["spectra"] = f"not estimated: {len(times)} compute steps (more than {SPECTRA_ROWS})"
        return
    from rbhyst.solve.history import body_spectrum_columns

    located = body_spectrum_columns(result.layout)
    raw = est.solution(rtol, times).raw(result.system)
    sink = body_sink(result.system, s)([label for label, _ in located])
    columns = [c for _, c in located]
    first = result.layout.table(raw.slice(0, 1))
    sink.update(first[:, columns], None, first[:, 0])
    i = 1
    for lo, hi, nsub in zip(bounds[:-1], bounds[1:], substeps):
        n = int(hi - lo) * int(nsub)
        for k in range(i, i + n, 65_536):
            part = result.layout.table(raw.slice(k, min(k + 65_536, i + n)))
            sink.update(part[:, columns], s.dt / int(nsub), part[:, 0])
        i += n
    ref = sink.result()
    # a spectrum the reference leaves at rest (a direction the scene does not move in: rounding
    # noise) is measured against the largest spectrum of the body, as column_errors does
    scale = max(float(np.max(ref.sa(loc, direction))) for loc, direction in ref.signals)
    for loc, direction in ref.signals:
        mine, theirs = result.spectra.sa(loc, direction), ref.sa(loc, direction)
        top = float(np.max(theirs))
        denom = top if top > AT_REST * scale else scale
        err = float(np.max(np.abs(mine - theirs))) / denom if denom > 0 else 0.0
        out["estimated_error"][f"{'srs' if s.spectra_kind == 'srs' else 'sa'}_{loc}_{direction}"] = err


def _halving(result, settings) -> dict:
    """The run again at dt/2: error ~ |x_h - x_h/2| 2^p / (2^p - 1) with the method's order p,
    at the same steps (every second one of the finer run)."""
    from rbhyst.solve import integrators
    from rbhyst.solve.plan import prepare

    order = integrators.get(settings.integrator).order
    planned = prepare(result.system, dataclasses.replace(settings, dt=settings.dt / 2, every=1))
    # the same compute nodes as the run's compared ones, every second of the finer run's (where
    # the run followed a record finer than dt, the finer run may take as many: matched by time)
    mine = result.compared[:, 0]
    doubled = planned.compute_steps == 2 * result.stats.steps * result.stats.record_substeps * result.stats.refine
    half = planned.run(keep=False, compare_every=2 * result.compare_every if doubled else None)
    theirs = half.compared[:, 0]
    at = np.clip(np.searchsorted(theirs, mine), 0, len(theirs) - 1)
    same = np.abs(theirs[at] - mine) <= 1e-9 * max(float(mine[-1]), 1.0)
    cols = estimate_columns(result.layout)
    keys, families = [k for k, _, _ in cols], [f for _, _, f in cols]
    diff = column_errors(result.compared[same, 1:], half.compared[at[same], 1:], keys, families, result.system)
    factor = 2.0**order / (2.0**order - 1.0)
    return {"estimated_error": dict(zip(keys, (float(factor * d) for d in diff))), "status": "step-halving",
            "method": f"step halving: |x(dt) - x(dt/2)| x 2^p/(2^p - 1), p = {order} (convergence on hysteretic "
                      "scenes is irregular: this can be optimistic)"}


#: a column whose peak stays below this fraction of its family's scale (a torsion beside the
#: rocking, a cross acceleration) warns only where its error is above warn_error of that scale
QUIET = 0.1


def family_terms(errors: dict, result) -> tuple[dict, set]:
    """(each column's error against its family's scale, the quiet columns): ``errors`` (key ->
    max_t |x - x_ref| / its scale, column_errors' measure) restated in the terms of the column's
    family (translations with translations, rotations at the radius of gyration, forces with
    forces, moments with moments, accelerations with accelerations: error_scales), from the
    run's own peaks; quiet: the columns whose peak is below QUIET of the family's scale. Nothing
    of either without a run (``result`` None or without its layout)."""
    if result is None or result.layout is None:
        return {}, set()
    cols = estimate_columns(result.layout)
    keys, families, columns = [k for k, _, _ in cols], [f for _, _, f in cols], [c for _, c, _ in cols]
    e = result.extremes
    peaks = np.maximum(np.abs(e.max[columns]), np.abs(e.min[columns]))
    own = error_scales(peaks, keys, families, result.system)
    family = family_scales(peaks, keys, families, result.system)
    out, quiet = {}, set()
    for k, p, o, f in zip(keys, peaks, own, family):
        if k in errors and f > 0:
            out[k] = errors[k] * o / f
            if p < QUIET * f:
                quiet.add(k)
    return out, quiet


def ranked(errors: dict, limit: float, family: dict | None = None, quiet=()) -> list[tuple[str, float]]:
    """The columns above ``limit`` that matter, largest first in their family's terms: (key,
    error). A quiet column (family_terms) counts only where its error in its family's terms is
    also above ``limit``: a column the scene leaves nearly at rest does not headline a warning."""
    family = family or {}
    over = [(k, v) for k, v in errors.items()
            if v > limit and (k not in quiet or family.get(k, v) > limit)]
    return sorted(over, key=lambda kv: (family.get(kv[0], kv[1]), kv[1]), reverse=True)


def warnings_for(accuracy: dict, settings, stats=None, result=None) -> list[str]:
    """The warnings an estimate calls for, with what would do. ``stats`` (the run's RunStats):
    where the stiffness monitor already split the steps, the error belongs to the split step,
    and the dt that would do is scaled from that. ``result``: the run, whose peaks put each
    error in its family's terms (family_terms: the warning lists those that matter first)."""
    if accuracy is None:
        return []
    if accuracy["status"] == "unavailable":
        return [f"the error could not be estimated: {accuracy['method']}"]
    err = accuracy["estimated_error"]
    over = ranked(err, settings.warn_error, *family_terms(err, result))
    name, worst = over[0] if over else ("", 0.0)
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
            step = settings.dt  # the compute step the error belongs to, where the run split dt
            if stats is not None:
                step = settings.dt / stats.record_substeps / stats.refine / 2**stats.max_substep_level
            dt = step * 0.5 * (settings.warn_error / worst) ** 0.5  # (a margin for the estimate's own error)
            hint = f"; dt = {dt:.3g} s, --integrator adaptive, or --tolerance {settings.warn_error:g} would do"
        else:
            hint = f"; --tolerance {settings.warn_error:g} would do"
        over = over[1:]
        also = ", ".join(f"{k} {v:.2%}" for k, v in over[:WARN_NAMES])
        also += f" and {len(over) - WARN_NAMES} more" if len(over) > WARN_NAMES else ""
        also = f" (also {also})" if also else ""
        out.append(f"estimated error {worst:.2%} in {name}{also} exceeds analysis.warn_error = "
                   f"{settings.warn_error:.0%}{hint}")
    return out


def meet_tolerance(system: System, settings, keep: bool = True, csv=None):
    """The run whose estimated error (largest over the estimate's columns: displacements, total
    accelerations, resultant, element forces, points) is at most settings.tolerance.

    The adaptive integration first, at rtol = tolerance x RTOL_PER_TOL, then 100 times tighter
    while the estimate exceeds the tolerance (each attempt's check is the next's answer, computed
    once); where reversals are so many that it exceeds its step budget, the deck's fixed-step
    method at dt, dt/2, dt/4 ... with step-halving estimates. The output stays on the deck's dt.
    An AnalysisError (exit 3) says what was reached where neither meets it.
    """
    from rbhyst.solve.history import Layout
    from rbhyst.solve.integrators.reference import TooManySteps
    from rbhyst.solve.plan import COMPARE_VALUES, output_steps, prepare

    tol = settings.tolerance
    system = at_rest_under_gravity(system)
    n_steps = output_steps(system, settings)
    layout = Layout(system, settings.points)
    stride = max(1, -(-(n_steps + 1) * (1 + len(estimate_columns(layout))) // COMPARE_VALUES))
    t = settings.dt * np.arange(n_steps + 1)
    est = Estimator(system, t[::stride], max_steps=STEP_BUDGET * max(n_steps, 1), layout=layout,
                    t_end=n_steps * settings.dt)
    rtol = min(1e-6, max(RTOL_MIN, tol * RTOL_PER_TOL))
    reached = None
    tic = time.perf_counter()
    try:
        while rtol >= RTOL_MIN:
            s = dataclasses.replace(settings, integrator="adaptive", rtol=rtol)
            acc = est.assess(est.values(rtol), rtol=rtol / CHECK_FACTOR, check=rtol)
            worst = max(acc["estimated_error"].values())
            spread_peaks = max(acc["peaks_spread"].values())
            reached = (worst, rtol)
            if worst <= tol:
                result = prepare(system, s).run(keep=keep, csv=csv)
                _add_spectra_errors(acc, result, est, rtol / CHECK_FACTOR)
                acc.update(status="estimated", tolerance=tol, wall_s=est.wall_s,
                           method=f"tolerance {tol:g}: the adaptive integration at rtol {rtol:g}, measured against "
                                  f"rtol {rtol / CHECK_FACTOR:g}", compared_steps=int(len(est.t)))
                result.accuracy = acc
                return result
            rtol /= CHECK_FACTOR
    except TooManySteps:
        return _ladder(system, settings, keep, csv, tic)
    worst, rtol = reached
    raise AnalysisError(
        f"tolerance {tol:g} not met: the adaptive integration reached {worst:.3g} at rtol {rtol:g} and does not "
        f"converge further (peaks differ by {spread_peaks:.2%}): the scene's history is sensitive to round-off; "
        f"a tolerance above {worst:.2g} can be met, or report the peaks")


#: the fixed-step ladder of tolerance mode halves dt at most this many times
LADDER_HALVINGS = 8


def _ladder(system: System, settings, keep, csv, tic):
    from rbhyst.solve.plan import prepare

    tol = settings.tolerance
    worst = math.inf
    for k in range(LADDER_HALVINGS + 1):
        s = dataclasses.replace(settings, dt=settings.dt / 2**k, every=settings.every * 2**k)
        result = prepare(system, s).run(keep=keep, csv=csv)
        acc = _halving(result, s)
        worst = max(acc["estimated_error"].values())
        if worst <= tol:
            acc.update(tolerance=tol, wall_s=time.perf_counter() - tic,
                       why="the adaptive integration exceeds its step budget on this scene (many reversals)",
                       compared_steps=int(len(result.compared)))
            result.accuracy = acc
            return result
    raise AnalysisError(f"tolerance {tol:g} not met: {settings.integrator} at dt = {settings.dt / 2**LADDER_HALVINGS:.3g} s "
                        f"reached {worst:.3g} (the adaptive integration exceeds its step budget here); "
                        "ask for a looser tolerance or a smaller analysis.dt")
