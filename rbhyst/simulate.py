"""simulate(system, ...) -> Result: the time grid, the load on it, and the compiled loop."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import integrators, kernels
from .errors import AnalysisError, InputError
from .model import System
from .results import Result


@dataclass(frozen=True)
class Settings:
    """How to integrate: the deck's [analysis] and output.every after command-line overrides."""

    integrator: str = "chang"
    dt: float = 1e-3
    duration: float | None = None
    every: int = 1
    max_omega_dt: float = 0.5
    max_substep_level: int = 12
    #: newmark: Newton correction <= newton_tol x the step's increment, at most newton_max_iter iterations
    newton_tol: float = 1e-10
    newton_max_iter: int = 20


def grid(system: System, s: Settings) -> tuple[int, int]:
    """(output steps, compute substeps per step): a record finer than dt is followed, not aliased."""
    duration = s.duration if s.duration is not None else system.excitation.duration
    if duration is None:
        raise InputError("analysis.duration: required when no record or finite pulse gives it")
    if s.dt > duration:
        raise InputError(f"analysis.dt: {s.dt} s is larger than the duration {duration} s")
    n_steps = max(1, math.ceil(duration / s.dt - 1e-9))
    fine = system.excitation.finest_dt
    nsub = max(1, math.ceil(s.dt / fine - 1e-9)) if fine else 1
    return n_steps, nsub


def simulate(system: System, s: Settings) -> Result:
    """Integrate M q'' + R(q) = p(t) from rest with the chosen method (seed eq. 11)."""
    method = integrators.get(s.integrator)
    if method.solve is not None:
        return method.solve(system, s)
    n_steps, nsub = grid(system, s)
    if n_steps < s.every:
        raise InputError(f"output.every: {s.every} is more than the {n_steps} steps of the analysis")
    h_c = s.dt / nsub
    t_c = h_c * np.arange(n_steps * nsub + 1)
    load = np.ascontiguousarray(system.excitation.load(t_c, system.mass))
    minv = 1.0 / system.mass
    k0 = system.K0
    level0 = min_level(system, s, method, h_c)
    # levels below level0 are never used (and may be singular for an extreme K0)
    coef = np.stack([method.coefficients(system.mass, k0, h_c / 2**max(lv, level0))
                     for lv in range(s.max_substep_level + 1)])

    d = np.zeros(3)
    v = np.zeros(3)
    a = minv * load[0]  # equilibrium at t = 0 with R(0) = 0: records rarely start at zero
    n_rows = n_steps // s.every + 1
    ne = system.bvec.shape[0]
    out_d = np.zeros((n_rows, 3))
    out_v = np.zeros((n_rows, 3))
    out_a = np.zeros((n_rows, 3))
    out_u = np.zeros((n_rows, ne))
    out_f = np.zeros((n_rows, ne))
    out_e = np.zeros((n_rows, 3))
    info = np.zeros(kernels.INFO_SIZE)
    args = (method.kernel_id, coef, minv, np.ascontiguousarray(system.bvec), system.mult,
            np.ascontiguousarray(system.params), load, h_c, nsub, n_steps, s.every,
            s.max_omega_dt, level0, s.max_substep_level, d, v, a,
            out_d, out_v, out_a, out_u, out_f, out_e, info, s.newton_tol, s.newton_max_iter)
    # load (or compile) the kernel before the clock starts: wall_s is time stepping only
    kernels.run(*args[:9], 0, *args[10:])  # n_steps = 0
    start = time.perf_counter()
    kernels.run(*args)
    wall = time.perf_counter() - start
    _raise_on_failure(system, s, info, nsub)

    t = s.dt * s.every * np.arange(n_rows)
    ag = system.excitation.support(t) if system.excitation.has_support else None
    return Result(
        system=system,
        settings=s,
        time=t,
        d=out_d,
        v=out_v,
        a=out_a,
        ag=ag,
        element_u=system.expand(out_u),
        element_f=system.expand(out_f),
        energy=out_e,
        steps=n_steps,
        record_substeps=nsub,
        min_substep_level=level0,
        substeps=int(info[kernels.I_SUBSTEPS]),
        max_substep_level=int(info[kernels.I_LEVEL]),
        max_omega_dt=float(info[kernels.I_OMEGA_DT]),
        steps_taken=int(info[kernels.I_STEPS]),
        newton_iterations=int(info[kernels.I_ITER]),
        wall_s=wall,
    )


def min_level(system: System, s: Settings, method, h: float) -> int:
    """Substep level that a structure-dependent method needs for omega_0 h <= the limit.

    Chang's displacement predictor scales the step's motion by (1 + (omega_0 h)^2 / 4)^-1
    where the tangent is softer than K0: accurate only while omega_0 h is small, whatever
    the current stiffness. omega_0^2 = max eig(M^-1 K0).
    """
    if not method.structure_dependent:
        return 0
    m = 1.0 / np.sqrt(system.mass)
    w0 = float(np.sqrt(np.max(np.linalg.eigvalsh(system.K0 * np.outer(m, m)))))
    level = max(0, math.ceil(math.log2(w0 * h / s.max_omega_dt))) if w0 * h > s.max_omega_dt else 0
    if level > s.max_substep_level:
        raise AnalysisError(
            f"omega_0 = {w0:.4g} rad/s of K0 (the elements' stiffness at a reversal) needs steps of "
            f"{s.max_omega_dt / w0:.3g} s with {s.integrator!r}: more than {2**s.max_substep_level} "
            f"substeps of dt = {s.dt:g} s; reduce dt"
        )
    return level


def _element_name(system: System, row: int) -> str:
    """'element e3' or 'elements e3, e4, e7' (CSV numbers) with the first one's place."""
    numbers = system.row_elements(row)
    el = next(el for el in system.elements if el.row == row)
    span = ("element " if len(numbers) == 1 else "elements ") + ", ".join(f"e{k}" for k in numbers)
    return f"{span} ({el.hysteresis!r} at ({el.x[0]:.4g}, {el.x[1]:.4g}) m, {el.angle_deg:g} deg)"


def _raise_on_failure(system: System, s: Settings, info: np.ndarray, nsub: int) -> None:
    status = int(info[kernels.I_STATUS])
    if status == kernels.OK:
        return
    t = info[kernels.I_TIME]
    e = int(info[kernels.I_ELEMENT])
    if status == kernels.OVERFLOW:
        p = system.params[e]
        raise AnalysisError(
            f"t = {t:.6g} s: {_element_name(system, e)} left its calibrated range: "
            f"beta2 u exceeded {700:g} (beta2 = {p[0, 4]:g}, {p[1, 4]:g} 1/m), so its force would overflow"
        )
    if status == kernels.UNRESOLVED:
        omega = info[kernels.I_OMEGA]
        k = info[kernels.I_STIFFNESS]
        raise AnalysisError(
            f"t = {t:.6g} s: {_element_name(system, e)} reached a tangent stiffness of {k:.4g} N/m "
            f"(omega_max = {omega:.4g} rad/s), which {2**s.max_substep_level} substeps of "
            f"dt = {s.dt:g} s cannot resolve; a step of {s.max_omega_dt / omega:.3g} s "
            "would (or raise analysis.max_substep_level)"
        )
    if status == kernels.NOT_CONVERGED:
        raise AnalysisError(
            f"t = {t:.6g} s: Newton iterations of {s.integrator!r} did not converge to "
            f"{s.newton_tol:g} in {s.newton_max_iter} iterations, even with {2**s.max_substep_level} "
            f"substeps of dt = {s.dt:g} s; reduce dt or use an explicit integrator"
        )
    raise AnalysisError(
        f"t = {t:.6g} s: the solution is no longer finite (NaN or Inf); the scene is numerically "
        f"unstable at dt = {s.dt:g} s with {s.integrator!r}"
    )


def settings_from_deck(deck, integrator: str | None = None, dt: float | None = None) -> Settings:
    """The deck's [analysis] and output.every, with command-line overrides validated like the deck."""
    from .deck import check_runnable

    check_runnable(deck)
    a = deck.analysis
    if integrator is not None and integrator not in integrators.names():
        raise InputError(f"--integrator: unknown {integrator!r}; choose one of {', '.join(integrators.names())}")
    if dt is not None and not dt > 0:
        raise InputError(f"--dt: {dt} must be > 0")
    return Settings(
        integrator=integrator or a.integrator,
        dt=dt or a.dt,
        duration=a.duration,
        every=deck.output.every,
        max_omega_dt=a.max_omega_dt,
        max_substep_level=a.max_substep_level,
    )
