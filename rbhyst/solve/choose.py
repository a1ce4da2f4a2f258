"""A run's answer within its accuracy: the compute step, and the kinematics, rbhyst chooses.

A deck that names no integrator states an accuracy (``analysis.warn_error``), not a step, as
the automatic time stepping of the commercial codes does (Abaqus/Standard's half-step residual
control, ANSYS' auto time stepping). rbhyst can do better than a residual: every run's estimate
(rbhyst.solve.estimate) states the error of every output and, for a method of order p, predicts
the step that meets the accuracy (error ~ h^p). So:

1. the first pass runs the default method at the deck's dt (dt being the output interval and a
   first guess); its estimate stops at the companion's number where that exceeds warn_error
   (a *screen*: the pass is not the answer);
2. where it exceeds warn_error, the next pass takes k compute steps per output step, k from the
   error and the order (aiming at AIM x warn_error, where the estimate needs no check of how
   determined the history is), and the rows stay on the deck's dt (output.every x k);
3. a pass whose estimate is within warn_error is the answer; so is a history that no step
   determines (status "sensitive": said as without the choice) and the last of MAX_PASSES.
   Past FIXED_LIMIT compute steps per output step the adaptive integration at the accuracy
   asked (tolerance mode) is cheaper than more fixed steps, and is tried instead.

With ``analysis.kinematics = "auto"`` the first pass also screens the kinematics
(rbhyst.solve.kinematic.needs_exact): where the terms the seed's small rotations neglect reach
a tenth of warn_error, the answer is the exact twin's run at the chosen step. Its error is the
small-rotation run's at the same step (their companion applies to the seed's rows only): the two
scenes differ by the kinematic difference D, and so do their errors, by a fraction of about D of
themselves; where D exceeds TRANSFER_LIMIT the exact run's own estimate (the adaptive solutions)
says it instead.

summary.json's ``analysis.chosen`` says what was chosen and why, with every pass.
"""

from __future__ import annotations

import dataclasses
import math
import time

from rbhyst.errors import AnalysisError
from rbhyst.model.system import System
from rbhyst.solve.result import Result

#: a refined pass aims at this fraction of warn_error: below the estimate's CHECK_ABOVE (0.5),
#: where it needs no check of the history's determinacy, with a margin for the prediction
AIM = 0.4
#: at most this many passes (the last is the answer, warned where it is not within warn_error)
MAX_PASSES = 4
#: beyond this many compute steps per output step the adaptive integration is tried instead
FIXED_LIMIT = 64
#: a refinement whose error falls slower than this order (error ~ h^order) says the history may
#: not be determined by any step: the pass is then estimated in full (its check says)
MIN_ORDER = 0.5
#: the small-rotation run's error stands for the exact twin's where the two differ by at most this
TRANSFER_LIMIT = 0.2


def estimated_run(system: System, settings, keep: bool = True, csv=None, planned=None, progress=None,
                  spare_core: bool = False, screen: bool = False) -> Result:
    """One run and its estimate (rbhyst.solve.estimate): its companion where it applies."""
    from rbhyst.solve.estimate import estimate
    from rbhyst.solve.plan import prepare

    planned = planned or prepare(system, settings)
    if keep:
        planned.check_size(keep=True)
    companion = companion_of(planned, spare_core) if settings.estimate else None
    result = planned.run(keep=keep, csv=csv, progress=progress, tap=companion and companion[1])
    if settings.estimate:
        if csv is not None:
            # the rows written first (their threads format them while the loop steps): an
            # estimate beside them took 30-60 % longer, and the two together no less time
            csv.wait()
        if progress is not None:
            progress(0, 0, "estimating the error")
        result.accuracy = estimate(result, settings, companion=companion, spare_core=spare_core, screen=screen)
    return result


def companion_of(planned, spare_core: bool = False):
    """(plan, tap) where the run's error can come from its companion (rbhyst.solve.companion): a
    tap of the whole run's rows, or for a long run one that steps the companion alongside it
    (rbhyst.solve.alongside: its memory a chunk's; on a thread of its own with a ``spare_core``)."""
    from rbhyst.solve import companion
    from rbhyst.solve.plan import FixedStepPlan, compare_stride

    if not isinstance(planned, FixedStepPlan) or companion.unfit(planned) is not None:
        return None
    if companion.whole_run_bytes(planned) > companion.WHOLE_RUN_BYTES:
        from rbhyst.solve.alongside import Alongside

        return planned, Alongside(planned, compare_stride(planned.layout, planned.compute_steps), beside=spare_core)
    return planned, companion.RunTap(planned)


def worst_of(accuracy: dict | None) -> tuple[float, str]:
    """(the largest estimated error, its column); (inf, "") where none was estimated."""
    err = (accuracy or {}).get("estimated_error")
    if not err:
        return math.inf, ""
    name = max(err, key=err.get)
    return float(err[name]), name


def compute_step(result: Result) -> float:
    """The finest regular compute step of a run (dt over the most substeps an output step takes
    to follow the excitation, times the refinement; the stiffness monitor's splits aside)."""
    st = result.stats
    return result.settings.dt / (st.record_substeps * st.refine)


def refinement(k: int, worst: float, target: float, order: float) -> int:
    """Compute steps per output step that bring an error ``worst`` at k of them to ``target``."""
    return max(k + 1, math.ceil(k * (worst / target) ** (1.0 / order) - 1e-9))


def chosen_run(system: System, settings, keep: bool = True, csv=None, progress=None,
               spare_core: bool = False) -> Result:
    """The answer within settings.warn_error (see the module docstring): a Result whose
    ``chosen`` says how it was reached. ``settings.kinematics`` "auto" lets the first pass
    choose the kinematics; the system is the small-rotation one then (assemble's)."""
    from rbhyst.solve import integrators
    from rbhyst.solve.kinematic import needs_exact

    s = settings
    warn = s.warn_error
    order = integrators.get(s.integrator).order
    tic = time.perf_counter()
    passes: list[dict] = []
    k, exact, share, where = 1, False, 0.0, ""
    small = None  # the small-rotation run at the last step tried
    result = None
    while True:
        sk = dataclasses.replace(s, refine=k, choose=False)
        last = len(passes) + 1 >= MAX_PASSES
        # the first pass is a trial (its rows are written only if it is the answer, once more):
        # later ones are expected to be the answer and write as they go
        trial = not passes
        small = estimated_run(system, sk, keep=keep if trial or not exact else False,
                              csv=None if trial or exact else csv, progress=progress, spare_core=spare_core,
                              screen=not last)
        if trial and s.kinematics == "auto":
            exact, share, where = needs_exact(small, s)
        passes.append(pass_entry(small, "small"))
        worst, status = worst_of(small.accuracy)[0], passes[-1]["status"]
        done = status in ("sensitive", "unavailable", "not estimated") or worst <= warn or last
        if done:
            break
        order_now = order
        if len(passes) >= 2 and passes[-2]["estimated_error"]:
            # the order the passes show (hysteretic scenes scatter about the method's)
            e1, k1 = passes[-2]["estimated_error"], passes[-2]["refine"]
            seen = math.log(e1 / worst) / math.log(k / k1) if worst > 0 and e1 > worst else 0.0
            if seen < MIN_ORDER:
                # a finer step hardly changed the error: is the history determined at all? This
                # pass's whole estimate says (its check; the adaptive solutions where it fails).
                # Determined, the first pass's step was not the one its error belongs to (the
                # stiffness monitor split it around the reversals): on at the method's order
                small = estimated_run(system, sk, keep=keep if not exact else False,
                                      csv=None if exact else csv, progress=progress, spare_core=spare_core)
                screened = passes.pop()
                passes.append(pass_entry(small, "small"))
                passes[-1]["wall_s"] += screened["wall_s"]
                worst, status = worst_of(small.accuracy)[0], passes[-1]["status"]
                trial = False
                if status != "estimated" or worst <= warn:
                    break
                seen = order
            order_now = min(max(seen, 1.0), order + 1.0)
        k_next = refinement(k, worst, AIM * warn, order_now)
        if k_next > FIXED_LIMIT:
            adaptive = _adaptive(system if not exact else None, small, s, keep, csv, passes, progress)
            if adaptive is not None:
                result = adaptive
                break
            k_next = FIXED_LIMIT  # (the adaptive integration could not: the finest fixed step allowed)
            if k >= FIXED_LIMIT:
                break
        k = k_next
    if result is None:
        result = answer_at(small, sk, exact, keep, csv, rerun=trial, progress=progress, passes=passes)
        if exact:
            result = _exact_finer(result, small, s, k, order, passes, keep, csv, progress, spare_core)
    why = _why(passes, warn, exact, share, where, result)
    result.chosen = {"method": result.settings.integrator,
                     "compute_step_s": compute_step(result), "kinematics": result.system.kinematics,
                     "passes": passes, "why": why,
                     # (every pass's time stepping and estimate: what analysis.wall_s + accuracy.wall_s
                     # are of one run; wall_s the whole choice, its Python and planning included)
                     "computing_wall_s": sum(p["wall_s"] for p in passes), "wall_s": time.perf_counter() - tic}
    return result


def pass_entry(run: Result, kinematics: str) -> dict:
    """analysis.chosen's entry of one pass: its method, step, kinematics, estimate and cost."""
    worst, name = worst_of(run.accuracy)
    return {"integrator": run.settings.integrator, "compute_step_s": compute_step(run), "kinematics": kinematics,
            "refine": run.settings.refine, "estimated_error": None if math.isinf(worst) else worst, "column": name,
            "status": run.accuracy["status"] if run.accuracy else "not estimated",
            "wall_s": run.stats.wall_s + (run.accuracy or {}).get("wall_s", 0.0)}


def _exact_finer(result: Result, small: Result, s, k: int, order: float, passes: list, keep, csv, progress,
                 spare_core) -> Result:
    """The exact answer refined while its own estimate (the adaptive solutions': no companion for
    exact rows) exceeds warn_error, as the small-rotation passes are (at most MAX_PASSES more)."""
    from rbhyst.model.kinematics import exact_twin

    warn = s.warn_error
    while ("transfer_gap" not in (result.accuracy or {}) and len(passes) < MAX_PASSES + 1
           and (result.accuracy or {}).get("status") == "estimated" and worst_of(result.accuracy)[0] > warn):
        k = refinement(k, worst_of(result.accuracy)[0], AIM * warn, order)
        kinematics = result.kinematics
        result = estimated_run(exact_twin(small.system), dataclasses.replace(s, refine=k, choose=False), keep=keep,
                               csv=csv, progress=progress, spare_core=spare_core)
        result.kinematics = kinematics
        passes.append(pass_entry(result, "exact"))
    return result


def answer_at(small: Result, sk, exact: bool, keep: bool, csv, rerun: bool, progress=None,
              passes: list | None = None) -> Result:
    """The answer at the step of the small-rotation run ``small``: that run itself (made once more
    where its rows are to be written and it was run without: ``rerun``), or the exact twin's run,
    its error from the small run's (the module docstring). ``passes``: analysis.chosen's, which
    the exact run joins."""
    from rbhyst.solve.kinematic import chosen_exact, difference, exact_run
    from rbhyst.solve.plan import prepare

    passes = [] if passes is None else passes
    if not exact:
        if rerun and csv is not None:
            # the same plan once more, its rows written: the same numbers to the bit (the
            # estimate, made on the first, stands)
            again = prepare(small.system, sk).run(keep=keep, csv=csv, compare_every=small.compare_every,
                                                  progress=progress)
            again.accuracy = small.accuracy
            return again
        return small
    answer = exact_run(small, sk, answer=True, keep=keep, csv=csv, progress=progress)
    if answer is None:  # (exact kinematics are built for the plane and the body in space)
        return small
    diff = difference(small, answer)
    gap = max(diff.values(), default=0.0) if diff else math.inf
    # (only the companion's estimate needs the transfer: the adaptive solutions follow exact
    # kinematics as they follow small ones)
    transfer = small.accuracy is not None and "companion" in small.accuracy and gap <= TRANSFER_LIMIT
    if transfer:
        answer.accuracy = transferred(small.accuracy, gap)
    elif sk.estimate:
        from rbhyst.solve.estimate import estimate

        answer.accuracy = estimate(answer, sk)
    passes.append({**pass_entry(answer, "exact"), "status": "the answer"})
    if transfer:  # (its estimate is the small run's, counted in that pass)
        passes[-1]["wall_s"] = answer.stats.wall_s
    answer.kinematics = chosen_exact(small, sk, answer)
    return answer


def transferred(accuracy: dict, gap: float) -> dict:
    """The small-rotation run's estimate as the exact twin's (see the module docstring), the
    fraction ``gap`` the two runs differ by said with it (``transfer_gap``)."""
    out = dict(accuracy)
    out["transfer_gap"] = gap
    out["method"] = (f"the small-rotation run's at the same step: the two scenes differ by {gap:.3g} at most, "
                     f"and their errors by about that fraction of themselves ({accuracy['method']})")
    return out


def _adaptive(system, small: Result, s, keep, csv, passes, progress) -> Result | None:
    """The adaptive integration at the accuracy asked (tolerance mode), where fixed steps would
    need more than FIXED_LIMIT a step of dt; None where it cannot meet it."""
    from rbhyst.model.kinematics import exact_twin
    from rbhyst.solve.estimate import meet_tolerance

    scene = system if system is not None else exact_twin(small.system)
    t = dataclasses.replace(s, tolerance=AIM * s.warn_error, choose=False)
    if progress is not None:
        progress(0, 0, f"the adaptive integration to {t.tolerance:g}")
    try:
        result = meet_tolerance(scene, t, keep=keep, csv=csv)
    except AnalysisError:
        return None
    worst, name = worst_of(result.accuracy)
    passes.append({"integrator": "adaptive", "compute_step_s": None, "refine": 1, "kinematics": scene.kinematics,
                   "rtol": result.settings.rtol, "estimated_error": worst, "column": name,
                   "status": result.accuracy.get("status", "estimated"),
                   "wall_s": result.stats.wall_s + result.accuracy.get("wall_s", 0.0)})
    return result


def _why(passes, warn: float, exact: bool, share: float, where: str, result) -> str:
    """One sentence: why the answer is the one it is."""
    first = passes[0]
    worst, _ = worst_of(result.accuracy)
    parts = []
    if first["estimated_error"] is not None and first["estimated_error"] <= warn:
        parts.append(f"the deck's dt meets warn_error = {warn:g} (estimated {first['estimated_error']:.3g})")
    elif first["estimated_error"] is not None:
        parts.append(f"at the deck's dt the estimated error was {first['estimated_error']:.3g} in {first['column']} "
                     f"(above warn_error = {warn:g}); "
                     + ("the adaptive integration meets it" if result.settings.integrator == "adaptive" else
                        f"a compute step of {compute_step(result):.3g} s gives {worst:.3g}"))
    else:
        parts.append(f"the error could not be estimated ({first['status']}): the deck's dt as given")
    if exact:
        parts.append(f"exact kinematics, as the terms the small rotations neglect reach {share:.3g} of {where}")
    if result.accuracy and result.accuracy.get("status") == "sensitive":
        parts.append("no step determines the history (sensitive)")
    return "; ".join(parts)
