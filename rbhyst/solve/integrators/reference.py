"""The reference solution: an adaptive 8th-order Runge-Kutta method between reversals.

Between two reversals every element stays on one branch (s, u_P, g_P), so its force
f(u) = c_s(u) - g_P exp(-s alpha (u - u_P)) is a smooth closed form (seed eq. 14) and
the equation of motion is an ordinary smooth ODE in (q, v):

    q' = v,  M v' = p(t) - sum mult b f(b . q) - C v,  E_in' = p . v  (seed eq. 11)

for a body of any number n of coordinates (the state is 2 n + 2 values).

It is integrated with DOP853 (Dormand and Prince's 8(5,3) pair with its 7th-order
dense output, Hairer, Norsett and Wanner, Solving ODEs I, II.10; the coefficient
tables are scipy's), compiled with numba. Two kinds of events end a step:

- a reversal: an element's velocity b . v crosses zero against its branch. Its time
  is located on the dense output (bisection-secant to round-off), the state there is
  the dense output's (the step, accepted, continued the old branch smoothly past it: no
  step is redone), and the element starts its new branch there, from the force it has
  (eq. 14 with t_P = the reversal). Interior double crossings are looked for
  on a cubic Hermite interpolant of b . v and, when suspected, on the dense output.
- a breakpoint of the load: a record's samples (between them it is linear, and so are
  its pieces) and an analytic signal's start, end and corners (between them the kernel
  evaluates the sine or pulse itself, exactly, at every time it asks; nothing is fitted
  or stored per step).

So the only error is the ODE solver's: local error per step below
atol + rtol |y| (rtol = 1e-12 by default; atol = rtol times a displacement scale from
the quasi-static response to the load with the elements' reversal stiffness, times
the lowest circular frequency for velocities). Hysteretic energy is the closed-form
work along each branch; input energy is integrated with the state.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from rbhyst.solve.integrators import dop853_tableau as _dop
from rbhyst.errors import AnalysisError
from rbhyst.solve.kernels.compiled import kernel
from rbhyst.solve.kernels.dop853_layout import (NS, P_FIRST, P_PHASE, P_ROWS, P_SIZE, P_T, R_ELEMENT, R_EVENTS, R_FEV,
    R_HMAX, R_HMIN, R_INFO, R_REJECTED, R_START_FLIPS, R_STATUS, R_STEPS, R_TIME, ST_NONFINITE, ST_OK, ST_OVERFLOW,
    ST_PAUSED, ST_STEP_TOO_SMALL, ST_TOO_MANY_STEPS, ny)
from rbhyst.model.kinematics import loads_at, rows_at
from rbhyst.model.records import Series
from rbhyst.model.signals import SINE
from rbhyst.solve.history import Layout, Raw
from rbhyst.solve.result import Result, RunStats
from rbhyst.solve.integrators import Method

RTOL = 1e-12
MAX_STEPS = 50_000_000

# DOP853 tables (12 stages, the 13th row is f at the end of the step, 3 more for dense output)
_A = np.ascontiguousarray(_dop.A, dtype=float)
_B = np.ascontiguousarray(_dop.B, dtype=float)
_C = np.ascontiguousarray(_dop.C, dtype=float)
_E3 = np.ascontiguousarray(_dop.E3, dtype=float)
_E5 = np.ascontiguousarray(_dop.E5, dtype=float)
_D = np.ascontiguousarray(_dop.D, dtype=float)


# --------------------------------------------------------------------------
# the load: records as linear pieces, analytic signals as they are
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Pieces:
    """The load as the kernel evaluates it: breakpoints (k + 1,), the records' share (with the
    constant load) at both ends of each piece (k, 2, n), and the analytic signals' table
    (signals, ROW_SIZE + n) evaluated exactly at every time the kernel asks; ``signals``: those
    signals and their weights into the load, for the same evaluation in Python."""

    brk: np.ndarray
    ends: np.ndarray
    analytic: np.ndarray
    signals: tuple = ()
    #: per system integrated, the tolerances' basis and the start (worked out once: an estimate
    #: may integrate the same scene twice)
    basis: dict = field(default_factory=dict, compare=False, repr=False)

    def at(self, t: np.ndarray) -> np.ndarray:
        """(len(t), n) the load at times t, as the kernel sees it (a jump at a breakpoint: its right side)."""
        t = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self.brk, t, side="right") - 1, 0, len(self.brk) - 2)
        ta, tb = self.brk[k], self.brk[k + 1]
        w = ((t - ta) / (tb - ta))[:, None]
        out = self.ends[k, 0] + w * (self.ends[k, 1] - self.ends[k, 0])
        mid = 0.5 * (ta + tb)
        for signal, weight in self.signals:
            stop = math.inf if signal.end is None else signal.end
            inside = (signal.start <= mid) & (mid <= stop)
            out += np.where(inside, signal.inside(t), 0.0)[:, None] * weight
        return out


def load_pieces(system, t_end: float) -> Pieces:
    """The load of ``system`` over [0, t_end] in pieces between breakpoints: a record's samples
    (between them it is linear, so linear pieces are exact) and an analytic signal's start, end
    and corners (between them it is smooth: the kernel evaluates it exactly, no fit and nothing
    stored per step, so memory stays that of the records however long or fast the signals)."""
    ex = system.excitation
    pts = [np.array([0.0, t_end])]
    for sig in ex.signals.values():
        tk = sig.times if isinstance(sig, Series) else np.asarray(sig.breakpoints, dtype=float)
        pts.append(tk[(tk > 0.0) & (tk < t_end)])
    brk = np.unique(np.concatenate(pts))
    keep = np.concatenate([[True], np.diff(brk) > 1e-12 * max(1.0, t_end)])
    brk = brk[keep]
    brk[-1] = t_end
    brk = np.ascontiguousarray(brk)
    weights = ex.weights(system.mass)
    analytic = tuple((s, weights[k]) for k, s in ex.signals.items() if not isinstance(s, Series))
    return Pieces(brk, np.ascontiguousarray(ex.record_pieces(brk, system.mass)),
                  np.ascontiguousarray(ex.analytic_table(system.mass)), analytic)


# --------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------


def _load_samples(pieces: Pieces, per_piece: int = 4, most: int = 200_000) -> np.ndarray:
    """(n, 3) the load at a few points of every piece (at most ``most`` points in all, and
    every sine's peaks reached to a few per cent): the scale the tolerances are set from."""
    brk = pieces.brk
    t = np.concatenate([brk, (brk[:-1, None] + np.diff(brk)[:, None] * np.arange(1, per_piece) / per_piece).ravel()])
    span = brk[-1] - brk[0]
    for row in pieces.analytic:
        if row[0] == SINE and row[2] > 0.0:
            t = np.concatenate([t, np.linspace(brk[0], brk[-1], int(min(most, 8 * row[2] * span / (2 * np.pi) + 2)))])
    if len(t) > most:
        t = np.random.default_rng(0).choice(t, most, replace=False)
    return pieces.at(np.sort(t))


def _scales(system, pieces: Pieces, rtol):
    """atol for (q, v): rtol x the quasi-static response to the load with the reversal stiffness;
    a rotation's at the radius of gyration sqrt(J / m) (J: its mass, m: the first translation's)."""
    spin = np.array([c.rotation for c in system.coordinates])
    m_t = system.mass[np.argmin(spin)] if not spin.all() else 1.0
    # lengths per unit of each coordinate: 1 for a translation, the radius of gyration for a rotation
    rg = np.where(spin, np.sqrt(system.mass / m_t), 1.0)
    if id(system) not in pieces.basis:
        pieces.basis[id(system)] = _basis(system, pieces, spin, rg)
    length, w1 = pieces.basis[id(system)]
    q = rtol * length * np.where(spin, 1.0 / rg, 1.0)
    return np.concatenate([q, q * w1, [0.0]]), length, w1


def _basis(system, pieces: Pieces, spin, rg):
    """The displacement scale and the lowest circular frequency the tolerances are set from."""
    kr = (system.bvec.T * (system.mult * system.k_reversal)) @ system.bvec
    p = _load_samples(pieces)[:, :system.n]  # the moments as at rest: a scale only
    try:
        static = np.linalg.solve(kr, p.T).T
    except np.linalg.LinAlgError:  # stiffnesses far apart (an absurd f0): singular in floating point
        static = np.linalg.lstsq(kr, p.T, rcond=None)[0].T
    length = max(float(np.max(np.abs(static[:, ~spin]), initial=0.0)),
                 float(np.max(np.abs(static[:, spin]) * rg[spin], initial=0.0)))
    if not length > 0.0:
        length = 1e-6
    m = 1.0 / np.sqrt(system.mass)
    w1 = math.sqrt(max(float(np.min(np.linalg.eigvalsh(kr * np.outer(m, m)))), 0.0)) or 1.0
    return length, w1


def _initial_state(system, pieces: Pieces):
    """(6, rows) branch sign, u_P, gap and antiderivative of every element row at the start, its
    stop's held peaks
    (gap NaN: virgin, worked out in the kernel), and q at the start: rest, at the static
    equilibrium under gravity when there is one, the elements as its path left them."""
    from rbhyst.solve.kernels.layout import A, DL, DU, G, S, U

    s0 = _initial_branches(system, pieces)
    init = np.zeros((6, len(s0)))  # (rows 4, 5: the stops' held peaks)
    init[0] = s0
    init[2] = np.nan
    y0 = np.zeros(system.n)
    static = getattr(system, "static", None)
    if static is not None:
        y0 = static.q.copy()
        moved = static.st[:, S] != 0.0
        init[0, moved] = static.st[moved, S]
        init[1, moved] = static.st[moved, U]
        init[2, moved] = static.st[moved, G]
        init[3, moved] = static.st[moved, A]
        init[4] = static.st[:, DL]
        init[5] = static.st[:, DU]
    return init, y0


def _initial_branches(system, pieces: Pieces):
    """Each element starts moving the way the initial acceleration (else the load's slope) pushes it."""
    first = pieces.brk[1] - pieces.brk[0]
    h = 1e-6 * first
    static = getattr(system, "static", None)
    q0 = static.q if static is not None else np.zeros(system.n)
    p0, p1 = loads_at(pieces.at(np.array([0.0, h])), q0[None], system.n, system.rotation_index, system.kernel_axial)
    dp0 = (p1 - p0) / h  # the load's slope at the start, from inside the first piece
    if static is not None:
        p0 = p0 - static.r  # the weight is carried by the elements
    a0 = p0 / system.mass
    j0 = dp0 / system.mass
    # the rows where the body starts (they differ from b only at a turned static equilibrium)
    rows = rows_at(system.bvec, system.kernel_axial, system.rotation_index, q0)
    s = np.sign(rows @ a0)
    s2 = np.sign(rows @ j0)
    s = np.where(s != 0, s, np.where(s2 != 0, s2, 1.0))
    return s.astype(float)


class TooManySteps(AnalysisError):
    """The adaptive integration ran past its budget of steps."""


@dataclass
class Solution:
    """What the integration gives at the output times: state (q, v, input energy, viscous work),
    element rows' deformation and force, hysteretic work."""

    t: np.ndarray
    y: np.ndarray  # (rows, 2 n + 2): q, v, input energy, viscous work
    eu: np.ndarray
    ef: np.ndarray
    eh: np.ndarray
    stats: dict
    stops: np.ndarray | None = None  # (rows, 4) as rbhyst.solve.plan.stop_record's

    @property
    def n(self) -> int:
        """The body's number of coordinates."""
        return (self.y.shape[1] - 2) // 2

    @property
    def q(self) -> np.ndarray:
        return self.y[:, :self.n]

    def raw(self, system) -> Raw:
        """The rows as a run's table takes them (rbhyst.solve.history)."""
        n = self.n
        v = self.y[:, n:2 * n]
        energy = np.column_stack([self.y[:, 2 * n], 0.5 * (v * v) @ system.mass, self.eh, self.y[:, 2 * n + 1]])
        return Raw(t=self.t, d=self.q, v=v, u=self.eu, f=self.ef, e=energy)


#: output rows a streamed run's adaptive integration holds at a time (and per call of its kernel)
WINDOW_ROWS = 32_768


class Integration:
    """The adaptive integration of ``system`` from rest over ``n_rows`` output rows, whose times
    ``times(lo, hi)`` gives (rows lo .. hi - 1, increasing, from 0), taken a block at a time
    (:meth:`take`): its memory is a window's rows, however long the run. The compiled kernel
    pauses where a step would need rows past those it was given and goes on from there, so the
    rows are the same to the bit however they are taken (tests/test_reference_windows.py).

    ``pieces``: the load from :func:`load_pieces`, when a caller integrates the same scene twice;
    ``max_steps``: a budget of steps (events cost one each)."""

    def __init__(self, system, n_rows: int, times, rtol: float = RTOL, pieces=None, max_steps: int = MAX_STEPS,
                 window: int = WINDOW_ROWS, t_end: float | None = None):
        self.system, self.n_rows, self.times, self.rtol = system, int(n_rows), times, rtol
        self.window = max(1, int(window))
        self.max_steps = max_steps
        t_end = float(times(n_rows - 1, n_rows)[0]) if t_end is None else t_end
        self.pieces = pieces if pieces is not None else load_pieces(system, t_end)
        brk, coef, sig = self.pieces.brk, self.pieces.ends, self.pieces.analytic
        self.atol, self.length, self.w1 = _scales(system, self.pieces, rtol)
        ne, n = system.bvec.shape
        self.width, self.ne = ny(n), ne
        if ("start", id(system)) not in self.pieces.basis:
            self.pieces.basis[("start", id(system))] = _initial_state(system, self.pieces)
        self.init, y0 = (a.copy() for a in self.pieces.basis[("start", id(system))])
        self.info = np.zeros(R_INFO)
        self.at = np.zeros(P_SIZE)
        # M^-1 as a tuple: its length n is a constant of the compiled kernel (one compilation per n)
        minv = tuple(1.0 / system.mass)
        self.args = (minv, np.ascontiguousarray(system.bvec), system.kernel_axial, system.rotation_index, system.mult,
                     system.kernel_params, np.ascontiguousarray(system.kernel_damping))
        self.work = (np.zeros((13, ne)), np.zeros((7, self.width)), np.zeros((16, self.width)), np.zeros((7, self.width)),
                     np.zeros((4, max(system.excitation.width, ne))), np.zeros(NS + 1))
        self.head = (rtol, self.atol, self.init, y0, 1e-6, int(max_steps), _A, _B, _C, _E3, _E5, _D)
        self._kernel = kernel("integrate", n)
        # compile (or load) before the clock starts, on a problem of one short piece (the first piece
        # may be the whole run: an analytic signal's)
        warm = np.zeros(P_SIZE)
        warm[P_ROWS] = 1
        self._kernel(*self.args, np.array([0.0, min(brk[1], 1e-6 * (brk[1] - brk[0]) + 1e-12)]), coef[:1].copy(), sig,
                     np.zeros(1), *self.head, *self._buffers(1)[1:], self.info, *self.work, warm)
        self.info[:] = 0.0
        self.at[P_ROWS] = self.n_rows
        self.wall_s = 0.0
        self._buf = self._buffers(0)
        self._lo = self._hi = 0  # rows lo .. hi - 1 are computed and not yet taken

    def _buffers(self, rows: int):
        return (np.zeros(rows), np.zeros((rows, self.width)), np.zeros((rows, self.ne)), np.zeros((rows, self.ne)),
                np.zeros(rows))

    def take(self, hi: int) -> Solution:
        """Rows from the first not yet taken to hi - 1 (the last block: the solver's stats and stops)."""
        size = self.window
        while self._hi < hi:
            want = max(size, hi - self._hi)
            self._room(want)
            off = self._hi - self._lo  # (where the rows after those kept go in the buffers)
            top = min(self.n_rows, self._hi + want)
            t, y, eu, ef, eh = (b[off:off + top - self._hi] for b in self._buf)
            t[:] = self.times(self._hi, top)
            self.at[P_FIRST] = self._hi
            before = (self.at[P_T], self.at[P_PHASE])
            tic = time.perf_counter()
            rows = self._kernel(*self.args, self.pieces.brk, self.pieces.ends, self.pieces.analytic, t, *self.head,
                                y, eu, ef, eh, self.info, *self.work, self.at)
            self.wall_s += time.perf_counter() - tic
            self._check(rows)
            if rows == self._hi and (self.at[P_T], self.at[P_PHASE]) == before:
                size *= 2  # (one step covers more rows than were given: give more)
            self._hi = rows
        lo, kept = self._lo, self._hi - self._lo
        whole = lo == 0 and hi == self.n_rows == len(self._buf[0])
        t, y, eu, ef, eh = (b if whole else b[:hi - lo].copy() for b in self._buf)
        if not whole:  # the rows computed past hi go to the buffers' start
            for b in self._buf:
                b[:kept - (hi - lo)] = b[hi - lo:kept]
        self._lo = hi
        last = hi == self.n_rows
        return Solution(t, y, eu, ef, eh, self.stats() if last else {}, self.stops() if last else None)

    def _room(self, more: int) -> None:
        """Buffers for the rows not yet taken (at their start) and ``more`` after them."""
        kept = self._hi - self._lo
        if len(self._buf[0]) < kept + more:
            new = self._buffers(kept + more)
            for a, b in zip(new, self._buf):
                a[:kept] = b[:kept]
            self._buf = new

    def _check(self, rows: int) -> None:
        status = int(self.info[R_STATUS])
        if status == ST_OK and rows == self.n_rows or status == ST_PAUSED:
            return
        t, rtol = self.info[R_TIME], self.rtol
        if status == ST_OVERFLOW:
            raise AnalysisError(f"t = {t:.6g} s: the adaptive solution took element {int(self.info[R_ELEMENT]) + 1} "
                                "(distinct elements, deck order) out of its calibrated range (exp overflow)")
        if status == ST_TOO_MANY_STEPS:
            raise TooManySteps(f"t = {t:.6g} s: the adaptive solution (rtol {rtol:g}) took more than "
                               f"{int(self.max_steps)} steps (reversals are events: each costs a step)")
        why = {ST_STEP_TOO_SMALL: "its step size fell below round-off",
               ST_NONFINITE: "the solution is no longer finite"}.get(status, "it stopped early")
        raise AnalysisError(f"t = {t:.6g} s: the adaptive solution (rtol {rtol:g}) failed: {why}")

    def stats(self) -> dict:
        info, n = self.info, self.system.n
        return {
            "method": "DOP853: explicit Runge-Kutta 8(5,3) with 7th-order dense output (Hairer-Norsett-Wanner), "
                      "compiled with numba",
            "rtol": self.rtol,
            "atol_q": self.atol[:n].tolist(),
            "atol_v": self.atol[n:2 * n].tolist(),
            "atol_basis": {"displacement_scale_m": self.length, "lowest_circular_frequency_rad_s": self.w1},
            "events": "reversals: element velocity b.v crossing zero against its branch, located on the dense "
                      "output and stepped to exactly; load breakpoints: record samples (linear between them), the "
                      "ends and corners of analytic signals (evaluated exactly between them)",
            "load_pieces": int(len(self.pieces.ends)),
            "steps": int(info[R_STEPS]),
            "rejected_steps": int(info[R_REJECTED]),
            "reversals": int(info[R_EVENTS]),
            "branch_corrections_at_step_start": int(info[R_START_FLIPS]),
            "rhs_evaluations": int(info[R_FEV]),
            "smallest_step_s": float(info[R_HMIN]),
            "largest_step_s": float(info[R_HMAX]),
            "wall_s": self.wall_s,
        }

    def stops(self) -> np.ndarray | None:
        """(rows, 4) as rbhyst.solve.plan.stop_record's, at the end; None for a scene without stops."""
        system, init = self.system, self.init
        if not system.has_stops:
            return None
        ms = self.work[0][6:13]  # the stops' (kernels.dop853._stops_at): the loss counted from the start (a
        # contact the weight rests on has lost what its loading did)
        lost = ms[2] + _open_loss(system, ms[0], ms[1]) - _open_loss(system, init[4], init[5])
        return np.ascontiguousarray(np.column_stack([ms[3], lost, ms[4], ms[5]]))


def integrate(system, t_out: np.ndarray, rtol: float = RTOL, pieces=None, max_steps: int = MAX_STEPS) -> Solution:
    """Integrate from rest to t_out[-1] with output at the increasing times t_out (from 0), all
    at once (:class:`Integration` takes them a block at a time, to the same bits).

    ``pieces``: the load from :func:`load_pieces`, when a caller
    integrates the same scene twice; ``max_steps``: a budget of steps (events cost one each).
    Raises AnalysisError where it cannot finish (TooManySteps past the budget).
    """
    t_out = np.ascontiguousarray(t_out, dtype=float)
    run = Integration(system, len(t_out), lambda lo, hi: t_out[lo:hi], rtol, pieces, max_steps, window=len(t_out),
                      t_end=float(t_out[-1]))
    return run.take(len(t_out))


def _split_times(bounds: np.ndarray, substeps: np.ndarray, dt: float):
    """times(lo, hi): rows lo .. hi - 1 of t = 0 followed by plan.compute_times(bounds, substeps,
    dt), the same values, without the whole array."""
    starts = np.concatenate([[1], 1 + np.cumsum(np.diff(bounds) * substeps)])

    def times(lo: int, hi: int) -> np.ndarray:
        out = np.empty(hi - lo)
        if lo == 0:
            out[0] = 0.0
        for i in range(max(0, np.searchsorted(starts, lo, side="right") - 1), len(substeps)):
            a, b = max(lo, int(starts[i])), min(hi, int(starts[i + 1]))
            if a >= hi:
                break
            if a < b:
                m, first = int(substeps[i]), int(bounds[i]) * int(substeps[i])
                out[a - lo:b - lo] = dt * ((first + np.arange(a - int(starts[i]) + 1, b - int(starts[i]) + 1)) / m)
        return out

    return times


def _open_loss(system, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(rows,) what each row's contact on at peaks lower, upper has lost (0.5 K (1 - e^2) d_max^2)."""
    from rbhyst.model.hysteresis import STOP_E, STOP_K, STOP_ROW

    if not system.has_stops:
        return np.zeros(len(lower))
    p = system.kernel_params[:, STOP_ROW]
    return 0.5 * p[:, STOP_K] * (1.0 - p[:, STOP_E] ** 2) * np.maximum(lower, upper) ** 2


def solve_with_stats(system, settings, rtol: float = RTOL, t_out: np.ndarray | None = None,
                     keep: bool = True, csv=None) -> tuple[Result, dict]:
    """A Result of the adaptive integration and what it took (for study.json).

    Output at every t_n = n dt (rows every ``settings.every`` steps kept; with output.spectra
    also at every compute step where the excitation is split, which only the spectra see, as
    in a fixed-step run), or at the increasing times ``t_out`` (from 0) if given, all kept: a
    study asks for the union of several grids.
    """
    from rbhyst.solve.plan import Rows, body_sink, grid, run_spectra, splitting

    n_steps, _ = grid(system, settings)
    every = 1
    spectra = None  # (a study's union of grids is not uniform: no spectra there)
    # blocks of rows as Rows.add takes them: (rows, compute steps per output step), row 0 first
    blocks = [(1, 1)] if t_out is None else [(1, 1), (len(t_out) - 1, 1)]
    segmented = False
    if t_out is None:
        if n_steps < settings.every:
            from rbhyst.errors import InputError

            raise InputError(f"output.every: {settings.every} is more than the {n_steps} steps of the analysis")
        every = settings.every
        spectra = settings.spectra
        bounds, substeps = splitting(system, settings, n_steps)
        if spectra is not None or substeps.max() > 1:
            # the solution at every compute step the fixed-step methods would take: the spectra
            # are driven there, and the peaks between the rows are seen (Rows.add)
            times = _split_times(bounds, substeps, settings.dt)
            blocks += [(int(hi - lo) * int(m), int(m)) for lo, hi, m in zip(bounds[:-1], bounds[1:], substeps)]
            segmented = True
        else:
            times = lambda lo, hi: settings.dt * np.arange(lo, hi)  # noqa: E731
            blocks.append((n_steps, 1))
        n_rows, window = sum(b for b, _ in blocks), WINDOW_ROWS
    else:
        t_out = np.ascontiguousarray(t_out, dtype=float)
        times, n_rows = (lambda lo, hi: t_out[lo:hi]), len(t_out)
        window = n_rows
    run = Integration(system, n_rows, times, rtol, window=window)
    layout = Layout(system, settings.points)
    rows = Rows(layout, n_steps if segmented else n_rows - 1, every, keep, csv,
                spectra=None if spectra is None else body_sink(system, settings), dt=settings.dt,
                compute_steps=n_rows - 1)
    try:
        done = 0
        for size, sub in blocks:
            # (each block in pieces of whole output steps of at most a window's rows)
            piece = max(sub, window // sub * sub)
            for lo in range(done, done + size, piece):
                sol = run.take(min(done + size, lo + piece))
                rows.add(sol.raw(system), sub=sub)
            done += size
    finally:
        table = rows.close()
    stats = RunStats(steps=n_steps, steps_taken=sol.stats["steps"], wall_s=sol.stats["wall_s"])
    result = Result(system=system, settings=settings, columns=layout.names, table=table, extremes=rows.extremes,
                    plot=rows.plot, stats=stats, layout=layout, csv_path=rows.csv_path, compared=rows.compared,
                    compare_every=rows.compare_every, solver=sol.stats, stops=sol.stops,
                    spectra=run_spectra(system, settings, rows.body_spectra()))
    return result, sol.stats


def solve(system, settings, keep: bool = True, csv=None) -> Result:
    return solve_with_stats(system, settings, rtol=RTOL, keep=keep, csv=csv)[0]


METHOD = Method(
    name="reference",
    summary="adaptive DOP853 between reversals located as events: the study's reference (slow)",
    order=8,
    explicit=True,
    solve=solve,
)

