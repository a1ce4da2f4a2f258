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

import numpy as np
from numba import njit
from . import dop853_tableau as _dop

from ..errors import AnalysisError
from ..hysteresis import ALPHA, EXP_ARG_MAX, branch_eval, branch_row
from ..records import Series
from ..results import Result
from . import Method

RTOL = 1e-12
NP = 8  # load polynomial: degree NP - 1 on each piece
MAX_PIECE = 0.02  # s, longest piece of the load before the fit check splits it
FIT_TOL = 1e-12  # of the load's peak
NS = 8  # samples of b . v per step when looking for a crossing
SIMULTANEOUS = 1e-9  # reversals this close (fraction of the step) are one event
MAX_STEPS = 50_000_000

# DOP853 tables (12 stages, the 13th row is f at the end of the step, 3 more for dense output)
_A = np.ascontiguousarray(_dop.A, dtype=float)
_B = np.ascontiguousarray(_dop.B, dtype=float)
_C = np.ascontiguousarray(_dop.C, dtype=float)
_E3 = np.ascontiguousarray(_dop.E3, dtype=float)
_E5 = np.ascontiguousarray(_dop.E5, dtype=float)
_D = np.ascontiguousarray(_dop.D, dtype=float)

NY = 7  # q (3), v (3), input energy
NERR = 6  # components under error control (not the energy)

# info layout
R_STATUS, R_TIME, R_ELEMENT, R_STEPS, R_REJECTED, R_EVENTS, R_FEV, R_HMIN, R_HMAX, R_START_FLIPS = range(10)
R_INFO = 10
ST_OK, ST_OVERFLOW, ST_STEP_TOO_SMALL, ST_TOO_MANY_STEPS, ST_NONFINITE = range(5)


# --------------------------------------------------------------------------
# compiled core
# --------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always")
def _force(params, e, s, up, gp, u):
    """Force of element e on the branch (s, u_P, g_P) at u (eq. 14) and C_s(u); ok False on overflow."""
    row = branch_row(s)
    c, kc, big, ok = branch_eval(params, e, row, s, u)
    x = -s * params[e, row, ALPHA] * (u - up)
    if not ok or x > EXP_ARG_MAX:
        return 0.0, 0.0, False
    return c - gp * math.exp(x), big, True


@njit(cache=True, error_model="numpy", inline="always")
def _load(t, k, brk, pcoef, out):
    ta = brk[k]
    tb = brk[k + 1]
    x = (2.0 * t - ta - tb) / (tb - ta)
    for c in range(3):
        acc = pcoef[k, NP - 1, c]
        for j in range(NP - 2, -1, -1):
            acc = acc * x + pcoef[k, j, c]
        out[c] = acc


@njit(cache=True, error_model="numpy")
def _rhs(t, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, dy):
    """dy = (v, M^-1 (p - R), p . v); returns the first element that overflowed, or -1."""
    _load(t, k, brk, pcoef, p)
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    for e in range(bvec.shape[0]):
        b0 = bvec[e, 0]
        b1 = bvec[e, 1]
        b2 = bvec[e, 2]
        f, _, ok = _force(params, e, s[e], up[e], gp[e], b0 * y[0] + b1 * y[1] + b2 * y[2])
        if not ok:
            return e
        mf = mult[e] * f
        r0 += mf * b0
        r1 += mf * b1
        r2 += mf * b2
    dy[0] = y[3]
    dy[1] = y[4]
    dy[2] = y[5]
    dy[3] = minv[0] * (p[0] - r0)
    dy[4] = minv[1] * (p[1] - r1)
    dy[5] = minv[2] * (p[2] - r2)
    dy[6] = p[0] * y[3] + p[1] * y[4] + p[2] * y[5]
    return -1


@njit(cache=True, error_model="numpy", inline="always")
def _dense(F, y_old, x, i):
    """Component i of the DOP853 dense output at x in [0, 1] of the step."""
    acc = F[6, i]
    acc = F[5, i] + x * acc
    acc = F[4, i] + (1.0 - x) * acc
    acc = F[3, i] + x * acc
    acc = F[2, i] + (1.0 - x) * acc
    acc = F[1, i] + x * acc
    acc = F[0, i] + (1.0 - x) * acc
    return y_old[i] + x * acc


@njit(cache=True, error_model="numpy", inline="always")
def _g_dense(F, y_old, x, bvec, e, s):
    """s_e (b_e . v) on the dense output: positive while the element moves along its branch."""
    w = bvec[e, 0] * _dense(F, y_old, x, 3) + bvec[e, 1] * _dense(F, y_old, x, 4) + bvec[e, 2] * _dense(F, y_old, x, 5)
    return s * w


@njit(cache=True, error_model="numpy")
def _integrate(minv, bvec, mult, params, brk, pcoef, t_out, rtol, atol, s_init, h_first,
               A, B, C, E3, E5, D, out_y, out_a, out_eu, out_ef, out_eh, info):
    ne = bvec.shape[0]
    n_int = brk.shape[0] - 1
    n_out = t_out.shape[0]
    s = s_init.copy()
    up = np.zeros(ne)
    gp = np.zeros(ne)
    ap = np.zeros(ne)  # C_s(u_P): antiderivative at the branch start
    wacc = np.zeros(ne)  # work of the element up to its branch start
    for e in range(ne):
        row = branch_row(s[e])
        c, kc, big, ok = branch_eval(params, e, row, s[e], 0.0)
        gp[e] = c  # the virgin state f = 0 at u = 0
        ap[e] = big

    y = np.zeros(NY)
    y_new = np.zeros(NY)
    y_ev = np.zeros(NY)
    ytmp = np.zeros(NY)
    f = np.zeros(NY)
    f_new = np.zeros(NY)
    K = np.zeros((16, NY))
    F = np.zeros((7, NY))
    p = np.zeros(3)
    yo = np.zeros(NY)
    gs = np.zeros(NS + 1)
    xroot = np.zeros(ne)  # where in the step each element reverses (2: not in this step)
    t = 0.0
    h = h_first
    io = 0
    n_steps = 0
    n_rej = 0
    n_ev = 0
    n_fev = 0
    n_start = 0
    h_min_seen = math.inf
    h_max_seen = 0.0
    exponent = -1.0 / 8.0

    for k in range(n_int):
        tb = brk[k + 1]
        bad = _rhs(t, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, f)
        n_fev += 1
        if bad >= 0:
            info[R_STATUS] = ST_OVERFLOW
            info[R_ELEMENT] = bad
            info[R_TIME] = t
            return io
        if io < n_out and t_out[io] <= t:
            # outputs at the start (t = 0) come from the state itself
            while io < n_out and t_out[io] <= t:
                for i in range(NY):
                    yo[i] = y[i]
                io = _write(io, t, k, yo, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc,
                            p, out_y, out_a, out_eu, out_ef, out_eh)
        while tb - t > 1e-13 * max(1.0, abs(tb)):
            if n_steps + n_rej > MAX_STEPS:
                info[R_STATUS] = ST_TOO_MANY_STEPS
                info[R_TIME] = t
                return io
            hh = h
            if t + hh >= tb - 1e-13 * max(1.0, abs(tb)):
                hh = tb - t
            if hh < 1e-14 * max(1.0, abs(t)):
                info[R_STATUS] = ST_STEP_TOO_SMALL
                info[R_TIME] = t
                return io
            # ---- one DOP853 step
            for i in range(NY):
                K[0, i] = f[i]
            bad = _stages(1, 12, t, hh, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, A, C, K, ytmp)
            n_fev += 11
            if bad < 0:
                for i in range(NY):
                    acc = 0.0
                    for j in range(12):
                        acc += B[j] * K[j, i]
                    y_new[i] = y[i] + hh * acc
                bad = _rhs(t + hh, y_new, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, f_new)
                n_fev += 1
            if bad >= 0:
                # an exponential overflowed inside the step: try a smaller one first
                if hh > 1e-9:
                    h = 0.25 * hh
                    n_rej += 1
                    continue
                info[R_STATUS] = ST_OVERFLOW
                info[R_ELEMENT] = bad
                info[R_TIME] = t
                return io
            for i in range(NY):
                K[12, i] = f_new[i]
            err5 = 0.0
            err3 = 0.0
            for i in range(NERR):
                sc = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
                a5 = 0.0
                a3 = 0.0
                for j in range(13):
                    a5 += E5[j] * K[j, i]
                    a3 += E3[j] * K[j, i]
                a5 /= sc
                a3 /= sc
                err5 += a5 * a5
                err3 += a3 * a3
            if err5 == 0.0 and err3 == 0.0:
                err = 0.0
            else:
                err = hh * err5 / math.sqrt((err5 + 0.01 * err3) * NERR)
            if not (err < math.inf):
                h = 0.25 * hh
                n_rej += 1
                continue
            if err > 1.0:
                h = hh * max(0.2, 0.9 * err ** exponent)
                n_rej += 1
                continue
            factor = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** exponent)
            # ---- events: an element's velocity crossing zero against its branch
            need = False
            for e in range(ne):
                g0 = s[e] * (bvec[e, 0] * y[3] + bvec[e, 1] * y[4] + bvec[e, 2] * y[5])
                g1 = s[e] * (bvec[e, 0] * y_new[3] + bvec[e, 1] * y_new[4] + bvec[e, 2] * y_new[5])
                if g1 < 0.0:
                    need = True
                    break
                # cubic Hermite of g over the step, from g and g' at both ends
                d0 = hh * s[e] * (bvec[e, 0] * f[3] + bvec[e, 1] * f[4] + bvec[e, 2] * f[5])
                d1 = hh * s[e] * (bvec[e, 0] * f_new[3] + bvec[e, 1] * f_new[4] + bvec[e, 2] * f_new[5])
                seen = g0 > 0.0
                for m in range(1, NS):
                    x = m / NS
                    h00 = (1.0 + 2.0 * x) * (1.0 - x) * (1.0 - x)
                    h10 = x * (1.0 - x) * (1.0 - x)
                    h01 = x * x * (3.0 - 2.0 * x)
                    h11 = x * x * (x - 1.0)
                    gm = h00 * g0 + h10 * d0 + h01 * g1 + h11 * d1
                    if gm < 0.0 and seen:
                        need = True
                        break
                    if gm > 0.0:
                        seen = True
                if need:
                    break
            have_dense = False
            ev = -1
            x_ev = 2.0
            if need:
                _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, minv, bvec, mult, params,
                                    s, up, gp, p, A, C, D, K, F, ytmp)
                n_fev += 3
                have_dense = True
                for e in range(ne):
                    xroot[e] = 2.0
                    se = s[e]
                    gs[0] = se * (bvec[e, 0] * y[3] + bvec[e, 1] * y[4] + bvec[e, 2] * y[5])
                    gs[NS] = se * (bvec[e, 0] * y_new[3] + bvec[e, 1] * y_new[4] + bvec[e, 2] * y_new[5])
                    for m in range(1, NS):
                        gs[m] = _g_dense(F, y, m / NS, bvec, e, se)
                    seen = gs[0] > 0.0
                    found = -1
                    for m in range(1, NS + 1):
                        if gs[m] < 0.0 and seen:
                            found = m
                            break
                        if gs[m] > 0.0:
                            seen = True
                    if found < 0:
                        if not seen and gs[NS] < 0.0:
                            # moving against its branch from the very start: flip it at t
                            xroot[e] = 0.0
                            if 0.0 < x_ev:
                                x_ev = 0.0
                                ev = e
                        continue
                    # root of g in [xa, xb], g(xa) >= 0 > g(xb): bisection-secant (Illinois)
                    xa = (found - 1) / NS
                    xb = found / NS
                    ga = gs[found - 1]
                    gb = gs[found]
                    side = 0
                    for _ in range(200):
                        if xb - xa <= 4e-16:
                            break
                        xm = (xa * gb - xb * ga) / (gb - ga) if ga != gb else 0.5 * (xa + xb)
                        if not (xa < xm < xb):
                            xm = 0.5 * (xa + xb)
                        gm = _g_dense(F, y, xm, bvec, e, se)
                        if gm == 0.0:
                            xa = xm
                            xb = xm
                            break
                        if gm > 0.0:
                            xa = xm
                            ga = gm
                            if side == 1:
                                gb *= 0.5
                            side = 1
                        else:
                            xb = xm
                            gb = gm
                            if side == -1:
                                ga *= 0.5
                            side = -1
                    xr = 0.5 * (xa + xb)
                    xroot[e] = xr
                    if xr < x_ev:
                        x_ev = xr
                        ev = e
            if ev >= 0 and x_ev == 0.0:
                # a branch chosen against the motion (a virgin element, or round-off at a reversal)
                for e in range(ne):
                    if xroot[e] == 0.0:
                        _new_branch(e, y, bvec, params, s, up, gp, ap, wacc)
                        n_start += 1
                bad = _rhs(t, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, f)
                n_fev += 1
                if n_start > 100 * (n_ev + n_steps + 10):
                    info[R_STATUS] = ST_STEP_TOO_SMALL
                    info[R_TIME] = t
                    return io
                continue
            if ev >= 0:
                t_ev = t + x_ev * hh
                # outputs before the reversal from this step's dense output
                while io < n_out and t_out[io] < t_ev:
                    x = (t_out[io] - t) / hh
                    for i in range(NY):
                        yo[i] = _dense(F, y, x, i)
                    io = _write(io, t_out[io], k, yo, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap,
                                wacc, p, out_y, out_a, out_eu, out_ef, out_eh)
                # redo the step to the reversal exactly
                h_ev = t_ev - t
                if h_ev > 0.0:
                    _stages(1, 12, t, h_ev, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, A, C, K, ytmp)
                    n_fev += 11
                    for i in range(NY):
                        acc = 0.0
                        for j in range(12):
                            acc += B[j] * K[j, i]
                        y_ev[i] = y[i] + h_ev * acc
                else:
                    for i in range(NY):
                        y_ev[i] = y[i]
                t = t_ev
                for i in range(NY):
                    y[i] = y_ev[i]
                while io < n_out and t_out[io] <= t:
                    io = _write(io, t_out[io], k, y, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc,
                                p, out_y, out_a, out_eu, out_ef, out_eh)
                # elements that reverse together (identical b and sets, or by chance within
                # SIMULTANEOUS of the step) all start their new branches here
                for e in range(ne):
                    if xroot[e] <= x_ev + SIMULTANEOUS:
                        _new_branch(e, y, bvec, params, s, up, gp, ap, wacc)
                        n_ev += 1
                n_steps += 1
                bad = _rhs(t, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, f)
                n_fev += 1
                if h_ev > 0.0:
                    h_min_seen = min(h_min_seen, h_ev)
                continue
            # ---- accept the whole step
            while io < n_out and t_out[io] < t + hh:
                if not have_dense:
                    _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, minv, bvec, mult, params,
                                        s, up, gp, p, A, C, D, K, F, ytmp)
                    n_fev += 3
                    have_dense = True
                x = (t_out[io] - t) / hh
                for i in range(NY):
                    yo[i] = _dense(F, y, x, i)
                io = _write(io, t_out[io], k, yo, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc,
                            p, out_y, out_a, out_eu, out_ef, out_eh)
            clipped = hh < h
            t = tb if hh == tb - t else t + hh
            for i in range(NY):
                y[i] = y_new[i]
                f[i] = f_new[i]
            n_steps += 1
            h_min_seen = min(h_min_seen, hh)
            h_max_seen = max(h_max_seen, hh)
            h = max(h, hh * factor) if clipped else hh * factor
            while io < n_out and t_out[io] <= t:
                io = _write(io, t_out[io], k, y, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc,
                            p, out_y, out_a, out_eu, out_ef, out_eh)
            if not (math.isfinite(y[0]) and math.isfinite(y[1]) and math.isfinite(y[2])):
                info[R_STATUS] = ST_NONFINITE
                info[R_TIME] = t
                return io
    # outputs left by round-off at the very end
    while io < n_out:
        io = _write(io, t_out[io], n_int - 1, y, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc,
                    p, out_y, out_a, out_eu, out_ef, out_eh)
    info[R_STATUS] = ST_OK
    info[R_STEPS] = n_steps
    info[R_REJECTED] = n_rej
    info[R_EVENTS] = n_ev
    info[R_FEV] = n_fev
    info[R_HMIN] = h_min_seen
    info[R_HMAX] = h_max_seen
    info[R_START_FLIPS] = n_start
    return io


@njit(cache=True, error_model="numpy")
def _stages(first, last, t, hh, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, A, C, K, ytmp):
    """Runge-Kutta stages first..last-1 of a step hh from (t, y) into the rows of K;
    returns the first element whose exponential overflowed, or -1."""
    for st in range(first, last):
        for i in range(NY):
            acc = 0.0
            for j in range(st):
                acc += A[st, j] * K[j, i]
            ytmp[i] = y[i] + hh * acc
        bad = _rhs(t + C[st] * hh, ytmp, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, K[st])
        if bad >= 0:
            return bad
    return -1


@njit(cache=True, error_model="numpy")
def _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p,
                        A, C, D, K, F, ytmp):
    """The three extra stages and the 7 rows of DOP853's dense output (as scipy's DOP853)."""
    _stages(13, 16, t, hh, y, k, brk, pcoef, minv, bvec, mult, params, s, up, gp, p, A, C, K, ytmp)
    for i in range(NY):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = hh * f[i] - dy
        F[2, i] = 2.0 * dy - hh * (f_new[i] + f[i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = hh * acc


@njit(cache=True, error_model="numpy", inline="always")
def _new_branch(e, y, bvec, params, s, up, gp, ap, wacc):
    """Element e reverses at the current state: a new branch from the force it has (eq. 14)."""
    u = bvec[e, 0] * y[0] + bvec[e, 1] * y[1] + bvec[e, 2] * y[2]
    f_old, big_old, _ = _force(params, e, s[e], up[e], gp[e], u)
    alpha = params[e, branch_row(s[e]), ALPHA]
    wacc[e] += big_old - ap[e] + s[e] * gp[e] * (math.exp(-s[e] * alpha * (u - up[e])) - 1.0) / alpha
    s[e] = -s[e]
    row = branch_row(s[e])
    c, kc, big, ok = branch_eval(params, e, row, s[e], u)
    up[e] = u
    gp[e] = c - f_old
    ap[e] = big


@njit(cache=True, error_model="numpy")
def _write(io, t, k, y, brk, pcoef, minv, bvec, mult, params, s, up, gp, ap, wacc, p,
           out_y, out_a, out_eu, out_ef, out_eh):
    """One output row at time t from the state y on the current branches."""
    _load(t, k, brk, pcoef, p)
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    eh = 0.0
    for e in range(bvec.shape[0]):
        u = bvec[e, 0] * y[0] + bvec[e, 1] * y[1] + bvec[e, 2] * y[2]
        fe, big, _ = _force(params, e, s[e], up[e], gp[e], u)
        alpha = params[e, branch_row(s[e]), ALPHA]
        w = wacc[e] + big - ap[e] + s[e] * gp[e] * (math.exp(-s[e] * alpha * (u - up[e])) - 1.0) / alpha
        out_eu[io, e] = u
        out_ef[io, e] = fe
        eh += mult[e] * w
        r0 += mult[e] * fe * bvec[e, 0]
        r1 += mult[e] * fe * bvec[e, 1]
        r2 += mult[e] * fe * bvec[e, 2]
    for i in range(NY):
        out_y[io, i] = y[i]
    out_a[io, 0] = minv[0] * (p[0] - r0)
    out_a[io, 1] = minv[1] * (p[1] - r1)
    out_a[io, 2] = minv[2] * (p[2] - r2)
    out_eh[io] = eh
    return io + 1


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


def _initial_branches(system, coef):
    """Each element starts moving the way the initial acceleration (else the load's slope) pushes it."""
    j = np.arange(NP)
    p0 = np.einsum("jc,j->c", coef[0], (-1.0) ** j)  # the load at t = 0 (x = -1) and its slope
    dp0 = np.einsum("jc,j->c", coef[0], j * (-1.0) ** (j - 1))
    a0 = p0 / system.mass
    j0 = dp0 / system.mass
    s = np.sign(system.bvec @ a0)
    s2 = np.sign(system.bvec @ j0)
    s = np.where(s != 0, s, np.where(s2 != 0, s2, 1.0))
    return s.astype(float)


def solve_with_stats(system, settings, rtol: float = RTOL, t_out: np.ndarray | None = None
                     ) -> tuple[Result, dict]:
    """The reference Result and what it took (for study.json).

    Output at t_n = n dt every ``settings.every`` steps, or at the increasing times
    ``t_out`` (from 0) if given: a study asks for the union of several grids.
    """
    from ..simulate import grid

    n_steps, _ = grid(system, settings)
    if t_out is None:
        if n_steps < settings.every:
            from ..errors import InputError

            raise InputError(f"output.every: {settings.every} is more than the {n_steps} steps of the analysis")
        t_out = settings.dt * settings.every * np.arange(n_steps // settings.every + 1)
    t_out = np.ascontiguousarray(t_out, dtype=float)
    t_end = float(t_out[-1])
    n_rows = len(t_out)
    brk, coef = load_pieces(system, t_end)
    atol, length, w1 = _scales(system, brk, coef, rtol)
    s0 = _initial_branches(system, coef)
    ne = system.bvec.shape[0]
    out_y = np.zeros((n_rows, NY))
    out_a = np.zeros((n_rows, 3))
    out_eu = np.zeros((n_rows, ne))
    out_ef = np.zeros((n_rows, ne))
    out_eh = np.zeros(n_rows)
    info = np.zeros(R_INFO)
    minv = 1.0 / system.mass
    args = (minv, np.ascontiguousarray(system.bvec), system.mult, np.ascontiguousarray(system.params))
    tail = (rtol, atol, s0, 1e-6, _A, _B, _C, _E3, _E5, _D, out_y, out_a, out_eu, out_ef, out_eh, info)
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
            raise AnalysisError(f"t = {t:.6g} s: the reference solution took element {int(info[R_ELEMENT]) + 1} "
                                "(distinct elements, deck order) out of its calibrated range (exp overflow)")
        why = {ST_STEP_TOO_SMALL: "its step size fell below round-off",
               ST_TOO_MANY_STEPS: f"it took more than {MAX_STEPS} steps",
               ST_NONFINITE: "the solution is no longer finite"}.get(status, "it stopped early")
        raise AnalysisError(f"t = {t:.6g} s: the reference solution failed: {why}")

    mass = system.mass
    d, v = out_y[:, :3], out_y[:, 3:6]
    energy = np.column_stack([out_y[:, 6], 0.5 * (v * v) @ mass, out_eh])
    ag = system.excitation.support(t_out) if system.excitation.has_support else None
    result = Result(
        system=system, settings=settings, time=t_out, d=d.copy(), v=v.copy(), a=out_a, ag=ag,
        element_u=system.expand(out_eu), element_f=system.expand(out_ef), energy=energy,
        steps=n_steps, wall_s=wall,
    )
    stats = {
        "method": "DOP853: explicit Runge-Kutta 8(5,3) with 7th-order dense output (Hairer-Norsett-Wanner), "
                  "compiled with numba",
        "rtol": rtol,
        "atol_q": atol[:3].tolist(),
        "atol_v": atol[3:6].tolist(),
        "atol_basis": {"displacement_scale_m": length, "lowest_circular_frequency_rad_s": w1},
        "events": "reversals: element velocity b.v crossing zero against its branch, located on the dense "
                  "output and stepped to exactly; load breakpoints: record samples and pieces of a degree-7 "
                  "fit to 1e-12 of the peak",
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
    return result, stats


def solve(system, settings) -> Result:
    return solve_with_stats(system, settings)[0]


METHOD = Method(
    name="reference",
    summary="adaptive DOP853 between reversals located as events: the study's reference (slow)",
    order=8,
    explicit=True,
    solve=solve,
)
