"""The reference solution: an adaptive 8th-order Runge-Kutta method between reversals.

Between two reversals every element stays on one branch (s, u_P, g_P), so its force
f(u) = c_s(u) - g_P exp(-s alpha (u - u_P)) is a smooth closed form (seed eq. 14) and
the equation of motion is an ordinary smooth ODE in (q, v):

    q' = v,  M v' = p(t) - sum mult b f(b . q),  E_in' = p . v.

It is integrated with DOP853 (Dormand and Prince's 8(5,3) pair with its 7th-order
dense output, Hairer, Norsett and Wanner, Solving ODEs I, II.10; the coefficient
tables are scipy's), compiled with numba. Two kinds of events end a step:

- a reversal: an element's velocity b . v crosses zero against its branch. Its time
  is located on the dense output (bisection-secant to round-off), the step is redone
  to exactly that time, and the element starts its new branch there, from the force
  it has (eq. 14 with t_P = the reversal). Interior double crossings are looked for
  on a cubic Hermite interpolant of b . v and, when suspected, on the dense output.
- a breakpoint of the load: support motion and forces are fitted piece by piece with
  degree-7 polynomials (Chebyshev nodes); a record's samples are breakpoints (between
  them it is linear, so the fit is exact) and a piece that does not fit to 1e-12 of
  the load's peak (a sine's end, any other kink) is split until it does.

So the only error is the ODE solver's: local error per step below
atol + rtol |y| (rtol = 1e-12 by default; atol = rtol times a displacement scale from
the quasi-static response to the load with the elements' reversal stiffness, times
the lowest circular frequency for velocities). Hysteretic energy is the closed-form
work along each branch; input energy is integrated with the state.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import dop853_tableau as _dop
from ..errors import AnalysisError
from ..kernels.compiled import kernel
from ..kernels.dop853_layout import (NP, NS, NY, R_ELEMENT, R_EVENTS, R_FEV, R_HMAX, R_HMIN, R_INFO, R_REJECTED,
                                     R_START_FLIPS, R_STATUS, R_STEPS, R_TIME, ST_NONFINITE, ST_OK, ST_OVERFLOW,
                                     ST_STEP_TOO_SMALL, ST_TOO_MANY_STEPS)
from ..records import Series
from ..history import Layout, Raw
from ..results import Result, RunStats
from . import Method

RTOL = 1e-12
MAX_PIECE = 0.02  # s, longest piece of the load before the fit check splits it
FIT_TOL = 1e-12  # of the load's peak
MAX_STEPS = 50_000_000

# DOP853 tables (12 stages, the 13th row is f at the end of the step, 3 more for dense output)
_A = np.ascontiguousarray(_dop.A, dtype=float)
_B = np.ascontiguousarray(_dop.B, dtype=float)
_C = np.ascontiguousarray(_dop.C, dtype=float)
_E3 = np.ascontiguousarray(_dop.E3, dtype=float)
_E5 = np.ascontiguousarray(_dop.E5, dtype=float)
_D = np.ascontiguousarray(_dop.D, dtype=float)


# --------------------------------------------------------------------------
# compiled core
# --------------------------------------------------------------------------
# the load as polynomial pieces
# --------------------------------------------------------------------------


def _nodes(n: int) -> np.ndarray:
    """Chebyshev points of the first kind on [-1, 1] (no end points: a jump sits on a breakpoint)."""
    return np.cos((2.0 * np.arange(n) + 1.0) * np.pi / (2.0 * n))[::-1]


def load_pieces(system, t_end: float, max_piece: float = MAX_PIECE, tol: float = FIT_TOL):
    """Breakpoints (n + 1,) and monomial coefficients (n, NP, 3) in x in [-1, 1] of each piece.

    A record's samples are breakpoints (it is linear between them); pieces are at most
    ``max_piece`` long, and any piece whose fit misses the load by more than ``tol`` times
    its peak (per component) at check points between the nodes is split in two.
    """
    ex = system.excitation
    pts = [np.array([0.0, t_end])]
    for sig in (ex.ag1, ex.ag2, ex.p1, ex.p2, ex.m3):
        if isinstance(sig, Series):
            tk = sig.t0 + sig.dt * np.arange(len(sig.values))
        elif sig is not None:
            tk = np.asarray(getattr(sig, "breakpoints", ()), dtype=float)  # a sine's or pulse's ends and corners
        else:
            continue
        pts.append(tk[(tk > 0.0) & (tk < t_end)])
    brk = np.unique(np.concatenate(pts))
    keep = np.concatenate([[True], np.diff(brk) > 1e-12 * max(1.0, t_end)])
    brk = brk[keep]
    brk[-1] = t_end
    lengths = np.diff(brk)
    split = np.maximum(1, np.ceil(lengths / max_piece - 1e-9)).astype(int)
    brk = np.concatenate([brk[i] + lengths[i] * np.arange(split[i]) / split[i] for i in range(len(lengths))]
                         + [[t_end]])
    xn = _nodes(NP)
    vinv = np.linalg.inv(np.vander(xn, NP, increasing=True))
    xc = np.concatenate([0.5 * (xn[:-1] + xn[1:]), [-0.999, 0.999]])
    vc = np.vander(xc, NP, increasing=True)
    mass = system.mass

    def fit(ta, tb):
        mid, half = 0.5 * (ta + tb), 0.5 * (tb - ta)
        vals = ex.load((mid[:, None] + half[:, None] * xn).ravel(), mass).reshape(len(ta), NP, 3)
        return np.einsum("jk,nkc->njc", vinv, vals)

    ta, tb = brk[:-1], brk[1:]
    coef = fit(ta, tb)
    scale = None
    for _ in range(60):
        mid, half = 0.5 * (ta + tb), 0.5 * (tb - ta)
        exact = ex.load((mid[:, None] + half[:, None] * xc).ravel(), mass).reshape(len(ta), len(xc), 3)
        approx = np.einsum("mj,njc->nmc", vc, coef)
        if scale is None:
            peak = np.max(np.abs(exact), axis=(0, 1))
            scale = np.where(peak > 0, peak, 1.0)
        bad = np.any(np.abs(approx - exact) > tol * scale, axis=(1, 2)) & (tb - ta > 1e-9)
        if not bad.any():
            break
        mids = 0.5 * (ta[bad] + tb[bad])
        new_ta = np.concatenate([ta[~bad], ta[bad], mids])
        new_tb = np.concatenate([tb[~bad], mids, tb[bad]])
        order = np.argsort(new_ta)
        new_coef = np.concatenate([coef[~bad], fit(ta[bad], mids), fit(mids, tb[bad])])
        ta, tb, coef = new_ta[order], new_tb[order], new_coef[order]
    brk = np.concatenate([ta, [tb[-1]]])
    return np.ascontiguousarray(brk), np.ascontiguousarray(coef)


# --------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------


def _scales(system, brk, coef, rtol):
    """atol for (q, v): rtol x the quasi-static response to the load with the reversal stiffness."""
    kr = (system.bvec.T * (system.mult * system.k_reversal)) @ system.bvec
    p = np.vstack([coef.sum(axis=1), np.einsum("njc,j->nc", coef, (-1.0) ** np.arange(NP))])  # piece ends
    static = np.linalg.solve(kr, p.T).T
    rg = math.sqrt(system.mass[2] / system.mass[0])
    length = max(float(np.max(np.abs(static[:, :2]))), float(np.max(np.abs(static[:, 2]))) * rg)
    if not length > 0.0:
        length = 1e-6
    m = 1.0 / np.sqrt(system.mass)
    w1 = math.sqrt(max(float(np.min(np.linalg.eigvalsh(kr * np.outer(m, m)))), 0.0)) or 1.0
    q = rtol * length * np.array([1.0, 1.0, 1.0 / rg])
    return np.concatenate([q, q * w1, [0.0]]), length, w1


def _initial_state(system, coef):
    """(4, rows) branch sign, u_P, gap and antiderivative of every element row at the start
    (gap NaN: virgin, worked out in the kernel), and q at the start: rest, at the static
    equilibrium under gravity when there is one, the elements as its path left them."""
    from ..kernels import A, G, S, U

    s0 = _initial_branches(system, coef)
    init = np.zeros((4, len(s0)))
    init[0] = s0
    init[2] = np.nan
    y0 = np.zeros(3)
    static = getattr(system, "static", None)
    if static is not None:
        y0 = static.q.copy()
        moved = static.st[:, S] != 0.0
        init[0, moved] = static.st[moved, S]
        init[1, moved] = static.st[moved, U]
        init[2, moved] = static.st[moved, G]
        init[3, moved] = static.st[moved, A]
    return init, y0


def _initial_branches(system, coef):
    """Each element starts moving the way the initial acceleration (else the load's slope) pushes it."""
    j = np.arange(NP)
    p0 = np.einsum("jc,j->c", coef[0], (-1.0) ** j)  # the load at t = 0 (x = -1) and its slope
    dp0 = np.einsum("jc,j->c", coef[0], j * (-1.0) ** (j - 1))
    static = getattr(system, "static", None)
    if static is not None:
        p0 = p0 - static.r  # the weight is carried by the elements
    a0 = p0 / system.mass
    j0 = dp0 / system.mass
    s = np.sign(system.bvec @ a0)
    s2 = np.sign(system.bvec @ j0)
    s = np.where(s != 0, s, np.where(s2 != 0, s2, 1.0))
    return s.astype(float)


class TooManySteps(AnalysisError):
    """The adaptive integration ran past its budget of steps."""


@dataclass
class Solution:
    """What the integration gives at the output times: state (q, v, input energy), equilibrium
    accelerations, element rows' deformation and force, hysteretic work."""

    t: np.ndarray
    y: np.ndarray  # (n, NY)
    a: np.ndarray
    eu: np.ndarray
    ef: np.ndarray
    eh: np.ndarray
    stats: dict

    @property
    def q(self) -> np.ndarray:
        return self.y[:, :3]


def integrate(system, t_out: np.ndarray, rtol: float = RTOL, pieces=None, max_steps: int = MAX_STEPS) -> Solution:
    """Integrate from rest to t_out[-1] with output at the increasing times t_out (from 0).

    ``pieces``: the load's (breakpoints, coefficients) from :func:`load_pieces`, when a caller
    integrates the same scene twice; ``max_steps``: a budget of steps (events cost one each).
    Raises AnalysisError where it cannot finish (TooManySteps past the budget).
    """
    t_out = np.ascontiguousarray(t_out, dtype=float)
    t_end = float(t_out[-1])
    n_rows = len(t_out)
    brk, coef = pieces if pieces is not None else load_pieces(system, t_end)
    atol, length, w1 = _scales(system, brk, coef, rtol)
    ne = system.bvec.shape[0]
    init, y0 = _initial_state(system, coef)
    out_y = np.zeros((n_rows, NY))
    out_a = np.zeros((n_rows, 3))
    out_eu = np.zeros((n_rows, ne))
    out_ef = np.zeros((n_rows, ne))
    out_eh = np.zeros(n_rows)
    info = np.zeros(R_INFO)
    minv = 1.0 / system.mass
    args = (minv, np.ascontiguousarray(system.bvec), system.mult, np.ascontiguousarray(system.params),
            np.ascontiguousarray(system.C))
    work = (np.zeros((6, ne)), np.zeros((7, NY)), np.zeros((16, NY)), np.zeros((7, NY)), np.zeros(3), np.zeros(NS + 1))
    tail = (rtol, atol, init, y0, 1e-6, int(max_steps), _A, _B, _C, _E3, _E5, _D, out_y, out_a, out_eu, out_ef, out_eh, info, *work)
    _integrate = kernel("integrate")
    # compile (or load) before the clock starts, on a one-piece problem
    _integrate(*args, brk[:2].copy(), coef[:1].copy(), t_out[:1].copy(), *tail)
    info[:] = 0.0
    start = time.perf_counter()
    rows = _integrate(*args, brk, coef, t_out, *tail)
    wall = time.perf_counter() - start
    status = int(info[R_STATUS])
    if status != ST_OK or rows != n_rows:
        t = info[R_TIME]
        if status == ST_OVERFLOW:
            raise AnalysisError(f"t = {t:.6g} s: the adaptive solution took element {int(info[R_ELEMENT]) + 1} "
                                "(distinct elements, deck order) out of its calibrated range (exp overflow)")
        if status == ST_TOO_MANY_STEPS:
            raise TooManySteps(f"t = {t:.6g} s: the adaptive solution (rtol {rtol:g}) took more than "
                               f"{int(max_steps)} steps (reversals are events: each costs a step)")
        why = {ST_STEP_TOO_SMALL: "its step size fell below round-off",
               ST_NONFINITE: "the solution is no longer finite"}.get(status, "it stopped early")
        raise AnalysisError(f"t = {t:.6g} s: the adaptive solution (rtol {rtol:g}) failed: {why}")
    stats = {
        "method": "DOP853: explicit Runge-Kutta 8(5,3) with 7th-order dense output (Hairer-Norsett-Wanner), "
                  "compiled with numba",
        "rtol": rtol,
        "atol_q": atol[:3].tolist(),
        "atol_v": atol[3:6].tolist(),
        "atol_basis": {"displacement_scale_m": length, "lowest_circular_frequency_rad_s": w1},
        "events": "reversals: element velocity b.v crossing zero against its branch, located on the dense "
                  "output and stepped to exactly; load breakpoints: record samples, the ends and corners of "
                  "analytic signals, and pieces of a degree-7 fit to 1e-12 of the peak",
        "load_pieces": int(len(coef)),
        "steps": int(info[R_STEPS]),
        "rejected_steps": int(info[R_REJECTED]),
        "reversals": int(info[R_EVENTS]),
        "branch_corrections_at_step_start": int(info[R_START_FLIPS]),
        "rhs_evaluations": int(info[R_FEV]),
        "smallest_step_s": float(info[R_HMIN]),
        "largest_step_s": float(info[R_HMAX]),
        "wall_s": wall,
    }
    return Solution(t_out, out_y, out_a, out_eu, out_ef, out_eh, stats)


def solve_with_stats(system, settings, rtol: float = RTOL, t_out: np.ndarray | None = None,
                     keep: bool = True, csv_path=None) -> tuple[Result, dict]:
    """A Result of the adaptive integration and what it took (for study.json).

    Output at every t_n = n dt (rows every ``settings.every`` steps kept), or at the increasing
    times ``t_out`` (from 0) if given, all kept: a study asks for the union of several grids.
    """
    from ..simulate import Rows, grid

    n_steps, _ = grid(system, settings)
    every = 1
    spectra = None  # (a study's union of grids is not uniform: no spectra there)
    if t_out is None:
        if n_steps < settings.every:
            from ..errors import InputError

            raise InputError(f"output.every: {settings.every} is more than the {n_steps} steps of the analysis")
        every = settings.every
        t_out = settings.dt * np.arange(n_steps + 1)
        spectra = settings.spectra
    sol = integrate(system, t_out, rtol)
    n_rows = len(sol.t)
    v = sol.y[:, 3:6]
    energy = np.column_stack([sol.y[:, 6], 0.5 * (v * v) @ system.mass, sol.eh, sol.y[:, 7]])
    raw = Raw(t=sol.t, d=sol.q, v=v, a=sol.a, u=sol.eu, f=sol.ef, e=energy)
    layout = Layout(system, settings.points)
    rows = Rows(layout, n_rows - 1, every, keep, csv_path, spectra=spectra, dt=settings.dt)
    try:
        rows.add(raw)
    finally:
        table = rows.close()
    stats = RunStats(steps=n_steps, steps_taken=sol.stats["steps"], wall_s=sol.stats["wall_s"])
    result = Result(system=system, settings=settings, columns=layout.names, table=table, extremes=rows.extremes,
                    plot=rows.plot, stats=stats, layout=layout, csv_path=csv_path, q_sample=rows.q_sample,
                    solver=sol.stats, spectra=rows.spectra_result())
    return result, sol.stats


def solve(system, settings, keep: bool = True, csv_path=None) -> Result:
    return solve_with_stats(system, settings, rtol=RTOL, keep=keep, csv_path=csv_path)[0]


METHOD = Method(
    name="reference",
    summary="adaptive DOP853 between reversals located as events: the study's reference (slow)",
    order=8,
    explicit=True,
    solve=solve,
)

