"""The adaptive integration's compiled kernel: DOP853 between reversals located as events.

See rbhyst.solve.integrators.reference for the method; this module holds only compiled code (the
driver there calls it through rbhyst.solve.kernels.compiled). The state is y = (q, v, input
energy, viscous work) of 2 n + 2 values for a body of n coordinates (dop853_layout.ny); n is the
length of the tuple minv, a compile-time constant, so that the loops over the coordinates unroll
(rbhyst.solve.integrators.steps says why).
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.model.hysteresis import ALPHA, EXP_ARG_MAX
from rbhyst.solve.kernels.dop853_layout import (NS, P_EVENTS, P_FEV, P_FIRST, P_H, P_HMAX, P_HMIN, P_IO, P_PHASE, P_PIECE, P_REJECTED, P_ROWS,
    P_START_FLIPS, P_STEPS, P_T, PH_END, PH_PIECE, PH_REST, PH_STEP, R_ELEMENT, R_EVENTS, R_FEV, R_HMAX, R_HMIN, R_REJECTED,
    R_START_FLIPS, R_STATUS, R_STEPS, R_TIME, SIMULTANEOUS, ST_NONFINITE, ST_OK, ST_OVERFLOW, ST_PAUSED, ST_STEP_TOO_SMALL,
    ST_TOO_MANY_STEPS)
from rbhyst.model.signals import HALF_SINE, HAVERSINE, ROW_SIZE as ROW, SAWTOOTH, SINE
from rbhyst.model.stop import STOP_E, STOP_K, STOP_LOWER, STOP_ROW, STOP_UPPER, stop_force
from rbhyst.model.vrm import branch_eval, branch_row
from rbhyst.solve.kernels.layout import SPATIAL
from rbhyst.solve.kernels.elements import turned_dampers
from rbhyst.solve.kernels.rotations import arm, attitude_rate, centripetal, rotation, turn_moments


# --------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _force(params, e, s, up, gp, u):
    """Force of element e on the branch (s, u_P, g_P) at u (eq. 14) and C_s(u); ok False on overflow."""
    row = branch_row(s)
    c, kc, big, ok = branch_eval(params, e, row, s, u)
    x = -s * params[e, row, ALPHA] * (u - up)
    if not ok or x > EXP_ARG_MAX:
        return 0.0, 0.0, False
    return c - gp * math.exp(x), big, True


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _analytic(sig, i, t, inside):
    """Analytic signal i of the table (rbhyst.model.signals row layout) at t; ``inside``: whether the
    piece being stepped lies within the signal's span (its ends are breakpoints, so a piece is
    inside or outside as a whole, and a jump at an end is seen from the piece's own side)."""
    if not inside:
        return 0.0
    kind = int(sig[i, 0])
    amp = sig[i, 1]
    start = sig[i, 4]
    if kind == SINE:
        v = amp * math.sin(sig[i, 2] * (t - start) + sig[i, 3])
        ramp = sig[i, 6]
        if ramp > 0.0:
            tau = min(max((t - start) / ramp, 0.0), 1.0)
            v *= tau - math.sin(2.0 * math.pi * tau) / (2.0 * math.pi)
        return v
    tau = min(max((t - start) / sig[i, 7], 0.0), 1.0)
    if kind == HALF_SINE:
        return amp * math.sin(math.pi * tau)
    if kind == HAVERSINE:
        return amp * 0.5 * (1.0 - math.cos(2.0 * math.pi * tau))
    if kind == SAWTOOTH:
        return amp * tau
    return amp * (1.0 - abs(2.0 * tau - 1.0))  # TRIANGLE


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _load(t, k, brk, pcoef, sig, out, n):
    """The load at t in piece k: the records' share linear between the piece's ends (exact: their
    samples are breakpoints), every analytic signal evaluated where it is (no fit, no table)."""
    ta = brk[k]
    tb = brk[k + 1]
    w = (t - ta) / (tb - ta)
    for c in range(n):
        out[c] = pcoef[k, 0, c] + w * (pcoef[k, 1, c] - pcoef[k, 0, c])
    mid = 0.5 * (ta + tb)
    for i in range(sig.shape[0]):
        v = _analytic(sig, i, t, sig[i, 4] <= mid <= sig[i, 5])
        if v != 0.0:
            for c in range(n):
                out[c] += sig[i, ROW + c] * v


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _turn_arm(load, y, rot, n):
    """Forces away from G with exact kinematics (load columns n, n + 1: r x p and r . p): the
    moment their turned arm adds at the state y, (cos(theta) - 1) (r x p) - sin(theta) (r . p)."""
    half = math.sin(0.5 * y[rot])
    load[rot] += -2.0 * half * half * load[n] - math.sin(y[rot]) * load[n + 1]


# a body in space with exact kinematics: each a function of its own, compiled once (not inlined
# at every call site of the plane's)
@njit(cache=True, error_model="numpy", _nrt=False)
def _u_spatial(bvec, axial, e, y):
    """Element e's deformation d . (u + R x - x) at y (rbhyst.solve.kernels.rotations.arm)."""
    t = arm(axial, e, rotation(y[3], y[4], y[5]))
    return bvec[e, 0] * y[0] + bvec[e, 1] * y[1] + bvec[e, 2] * y[2] + t[0]


@njit(cache=True, error_model="numpy", _nrt=False)
def _v_spatial(bvec, axial, e, y):
    """Element e's deformation rate b_e(q) . v, v = (u', omega) = y[6:12]."""
    t = arm(axial, e, rotation(y[3], y[4], y[5]))
    return (bvec[e, 0] * y[6] + bvec[e, 1] * y[7] + bvec[e, 2] * y[8]
            + t[1] * y[9] + t[2] * y[10] + t[3] * y[11])


@njit(cache=True, error_model="numpy", _nrt=False)
def _a_spatial(bvec, axial, e, y, f):
    """The derivative of _v_spatial: b_e(q) . v' and the point's centripetal acceleration along the line."""
    t = arm(axial, e, rotation(y[3], y[4], y[5]))
    return (bvec[e, 0] * f[6] + bvec[e, 1] * f[7] + bvec[e, 2] * f[8]
            + t[1] * f[9] + t[2] * f[10] + t[3] * f[11] + centripetal(axial, e, t, y[9], y[10], y[11]))


@njit(cache=True, error_model="numpy", _nrt=False)
def _g_spatial(F, y_old, x, bvec, axial, e):
    """_v_spatial on the dense output at x."""
    t = arm(axial, e, rotation(_dense(F, y_old, x, 3), _dense(F, y_old, x, 4), _dense(F, y_old, x, 5)))
    w = bvec[e, 0] * _dense(F, y_old, x, 6) + bvec[e, 1] * _dense(F, y_old, x, 7) + bvec[e, 2] * _dense(F, y_old, x, 8)
    return w + t[1] * _dense(F, y_old, x, 9) + t[2] * _dense(F, y_old, x, 10) + t[3] * _dense(F, y_old, x, 11)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _bdot(bvec, e, y, first, n):
    """b_e . y[first:first + n], summed from the first term (y at 0: q; at n: v)."""
    acc = bvec[e, 0] * y[first]
    for i in range(1, n):
        acc += bvec[e, i] * y[first + i]
    return acc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _u_el(bvec, axial, rot, e, y, n):
    """Element e's deformation at q = y[:n]: b_e . q, or with exact kinematics (rot >= 0)
    b_e . q with b_rot sin(theta) + axial_e (cos(theta) - 1) for b_rot theta
    (rbhyst.solve.kernels.elements.update_elements); in space (rot = SPATIAL) d . (u + R x - x)."""
    if rot == SPATIAL:
        return _u_spatial(bvec, axial, e, y)
    if rot < 0:
        return _bdot(bvec, e, y, 0, n)
    acc = 0.0
    for i in range(n):
        if i != rot:
            acc += bvec[e, i] * y[i]
    half = math.sin(0.5 * y[rot])
    return acc + bvec[e, rot] * math.sin(y[rot]) - 2.0 * axial[e] * half * half


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _v_el(bvec, axial, rot, e, y, n):
    """Element e's deformation rate b_e(q) . v at the state y = (q, v, ...)."""
    if rot == SPATIAL:
        return _v_spatial(bvec, axial, e, y)
    if rot < 0:
        return _bdot(bvec, e, y, n, n)
    acc = 0.0
    for i in range(n):
        if i != rot:
            acc += bvec[e, i] * y[n + i]
    return acc + (bvec[e, rot] * math.cos(y[rot]) - axial[e] * math.sin(y[rot])) * y[n + rot]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _a_el(bvec, axial, rot, e, y, f, n):
    """The time derivative of _v_el at the state y whose derivative is f = (v, a, ...):
    b_e(q) . a, plus omega^2 d2u_e/dtheta2 with exact kinematics (in space, the point's
    centripetal acceleration along the line)."""
    if rot == SPATIAL:
        return _a_spatial(bvec, axial, e, y, f)
    if rot < 0:
        return _bdot(bvec, e, f, n, n)
    acc = 0.0
    for i in range(n):
        if i != rot:
            acc += bvec[e, i] * f[n + i]
    cs = math.cos(y[rot])
    sn = math.sin(y[rot])
    w = y[n + rot]
    return acc + (bvec[e, rot] * cs - axial[e] * sn) * f[n + rot] - (bvec[e, rot] * sn + axial[e] * cs) * w * w


@njit(cache=True, error_model="numpy", _nrt=False)
def _rhs(t, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, dy):
    """dy = (v, M^-1 (p - R - C v), p . v, v . C v) (seed eq. 11); p (4, max(n, ne)) is work
    space (the load, R, C v, each element's mult f); returns the first element that
    overflowed, or -1."""
    n = len(minv)
    load = p[0]
    r = p[1]
    cv = p[2]
    mf = p[3]
    if rot == SPATIAL:  # a body in space, exact: its own axes (rbhyst.solve.kernels.rotations)
        return _rhs_spatial(t, y, k, brk, pcoef, sig, minv, bvec, axial, mult, params, cm, s, up, gp, ms, p, dy)
    if rot >= 0 and pcoef.shape[2] > n:  # forces whose arm turns with the body
        _load(t, k, brk, pcoef, sig, load, n + 2)
        _turn_arm(load, y, rot, n)
    else:
        _load(t, k, brk, pcoef, sig, load, n)
    stops = params.shape[1] > STOP_ROW
    for e in range(bvec.shape[0]):
        u = _u_el(bvec, axial, rot, e, y, n)
        f, _, ok = _force(params, e, s[e], up[e], gp[e], u)
        if not ok:
            return e
        if stops:
            fs, _ = stop_force(params, e, u, ms[0, e], ms[1, e])
            f += fs
        mf[e] = mult[e] * f
    for i in range(n):
        # R = sum mult f b, each component summed in a register in the elements' order
        acc = 0.0
        if i == rot:  # exact kinematics: the rotation's entry of b_e(q)
            cs = math.cos(y[rot])
            sn = math.sin(y[rot])
            for e in range(bvec.shape[0]):
                acc += mf[e] * (bvec[e, i] * cs - axial[e] * sn)
        else:
            for e in range(bvec.shape[0]):
                acc += mf[e] * bvec[e, i]
        r[i] = acc
    _finish_rhs(y, minv, cm, rot, load, r, cv, dy, n)
    return -1


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _finish_rhs(y, minv, cm, rot, load, r, cv, dy, n):
    """dy = (v, M^-1 (p - R - C v), p . v, v . C v) once p (in load) and R are known; dy[:n] is
    left to the caller where it is not v."""
    for i in range(n):
        dy[i] = y[n + i]
        acc = cm[i, 0] * y[n]
        for j in range(1, n):
            acc += cm[i, j] * y[n + j]
        cv[i] = acc
    if cm.shape[0] > n:
        turned_dampers(cm, rot, y, y, y, n, cv, 1.0, n)
    for i in range(n):
        dy[n + i] = minv[i] * (load[i] - r[i] - cv[i])
    power = load[0] * y[n]
    viscous = cv[0] * y[n]
    for i in range(1, n):
        power += load[i] * y[n + i]
        viscous += cv[i] * y[n + i]
    dy[2 * n] = power
    dy[2 * n + 1] = viscous


@njit(cache=True, error_model="numpy", _nrt=False)
def _rhs_spatial(t, y, k, brk, pcoef, sig, minv, bvec, axial, mult, params, cm, s, up, gp, ms, p, dy):
    """_rhs for a body in space with exact kinematics: q = (u, psi), v = (u', omega) with omega
    in the body's axes; psi' = J_r(psi)^-1 omega, M v' = p - R - C v - (0, omega x J omega), the
    moments of p and R in the body's axes (rbhyst.solve.kernels.rotations)."""
    n = len(minv)
    load = p[0]
    r = p[1]
    cv = p[2]
    mf = p[3]
    rm = rotation(y[3], y[4], y[5])
    if pcoef.shape[2] > n:  # forces away from G: their components, after the n loads
        _load(t, k, brk, pcoef, sig, load, n + 3)
        turn_moments(rm, load, load[n], load[n + 1], load[n + 2], axial)
    else:
        _load(t, k, brk, pcoef, sig, load, n)
        turn_moments(rm, load, 0.0, 0.0, 0.0, axial)
    for i in range(n):
        r[i] = 0.0
    stops = params.shape[1] > STOP_ROW
    ne = bvec.shape[0]
    for e in range(ne):
        a = arm(axial, e, rm)
        u = bvec[e, 0] * y[0] + bvec[e, 1] * y[1] + bvec[e, 2] * y[2] + a[0]
        f, _, ok = _force(params, e, s[e], up[e], gp[e], u)
        if not ok:
            return e
        if stops:
            fs, _ = stop_force(params, e, u, ms[0, e], ms[1, e])
            f += fs
        m = mult[e] * f
        r[0] += m * bvec[e, 0]
        r[1] += m * bvec[e, 1]
        r[2] += m * bvec[e, 2]
        r[3] += m * a[1]
        r[4] += m * a[2]
        r[5] += m * a[3]
    # Euler's term omega x J omega, with the restoring moments (J = diag(M^-1)^-1 in the principal axes)
    w0, w1, w2 = y[n + 3], y[n + 4], y[n + 5]
    k3 = n - 3  # (3: the index is not a literal, so that the plane's n = 3 compiles this too)
    j0, j1, j2 = 1.0 / minv[k3], 1.0 / minv[k3 + 1], 1.0 / minv[k3 + 2]
    r[3] += (j2 - j1) * w1 * w2
    r[4] += (j0 - j2) * w2 * w0
    r[5] += (j1 - j0) * w0 * w1
    _finish_rhs(y, minv, cm, SPATIAL, load, r, cv, dy, n)
    d0, d1, d2 = attitude_rate(y[3], y[4], y[5], y[n + 3], y[n + 4], y[n + 5])
    dy[3] = d0
    dy[4] = d1
    dy[5] = d2
    return -1


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
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


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _g_dense(F, y_old, x, bvec, axial, rot, e, s, n):
    """s_e (b_e(q) . v) on the dense output: positive while the element moves along its branch."""
    if rot == SPATIAL:
        return s * _g_spatial(F, y_old, x, bvec, axial, e)
    if rot < 0:
        w = bvec[e, 0] * _dense(F, y_old, x, n)
        for i in range(1, n):
            w += bvec[e, i] * _dense(F, y_old, x, n + i)
        return s * w
    w = 0.0
    for i in range(n):
        if i != rot:
            w += bvec[e, i] * _dense(F, y_old, x, n + i)
    th = _dense(F, y_old, x, rot)
    w += (bvec[e, rot] * math.cos(th) - axial[e] * math.sin(th)) * _dense(F, y_old, x, n + rot)
    return s * w


@njit(cache=True, error_model="numpy", _nrt=False)
def _integrate(minv, bvec, axial, rot, mult, params, cm, brk, pcoef, sig, t_out, rtol, atol, init, y0, h_first, max_steps,
               A, B, C, E3, E5, D, out_y, out_eu, out_ef, out_eh, info, el, vec, K, F, p, gs, at):
    """The integration, or its part whose output rows are t_out: rows at[P_FIRST] ..
    at[P_FIRST] + len(t_out) - 1 of at[P_ROWS] (out_* hold those rows). A call that would need a
    later row pauses before the step that needs it (info[R_STATUS] = ST_PAUSED) and records in
    ``at`` where it stopped; the next call, given the next rows and the same work space, goes on
    from there, so the steps, and every row, are the same to the bit however the rows are cut.

    el (13, ne), vec (7, ny), K (16, ny), F (7, ny), p (4, max(n, ne)), gs (NS + 1,) are its work
    space (allocated by the caller: no reference counting in here), y0 (n,) the start.

    One function, long, because numba keeps the stepper's state in registers only within a function.
    """
    ne = bvec.shape[0]
    n = len(minv)
    ny = 2 * n + 2  # q, v, input energy, viscous work
    nerr = 2 * n  # under error control: not the energies
    n_int = brk.shape[0] - 1
    n_out = int(at[P_ROWS])
    io0 = int(at[P_FIRST])
    lim = min(n_out, io0 + t_out.shape[0])  # rows up to lim - 1 are at hand
    phase = int(at[P_PHASE])
    s = el[0]
    up = el[1]
    gp = el[2]
    ap = el[3]  # C_s(u_P): antiderivative at the branch start
    wacc = el[4]  # work of the element up to its branch start
    ms = el[6:13]  # the stops' (_stops_at), from init's rows 4 and 5 (their held peaks); 6: their work at the start
    y = vec[0]
    if phase == PH_REST:
        el[:, :] = 0.0
        vec[:, :] = 0.0
        for e in range(ne):
            # init rows: branch sign, its start u_P, the gap there, the antiderivative there
            s[e] = init[0, e]
            up[e] = init[1, e]
            if math.isnan(init[2, e]):  # virgin: f = 0 at u = 0
                row = branch_row(s[e])
                c, kc, big, ok = branch_eval(params, e, row, s[e], 0.0)
                gp[e] = c
                ap[e] = big
            else:
                gp[e] = init[2, e]
                ap[e] = init[3, e]
            if init.shape[0] > 5:
                ms[0, e] = init[4, e]
                ms[1, e] = init[5, e]
        for i in range(n):
            y[i] = y0[i]
        if params.shape[1] > STOP_ROW:  # the stops' work is counted from the start, as the elements'
            for e in range(ne):
                _, ms[6, e] = stop_force(params, e, _u_el(bvec, axial, rot, e, y, n), ms[0, e], ms[1, e])
    y_new = vec[1]
    y_ev = vec[2]
    ytmp = vec[3]
    f = vec[4]
    f_new = vec[5]
    yo = vec[6]
    xroot = el[5]  # where in the step each element reverses (2: not in this step)
    if phase == PH_REST:
        t = 0.0
        h = h_first
        io = 0
        k_first = 0
        n_steps = 0
        n_rej = 0
        n_ev = 0
        n_fev = 0
        n_start = 0
        h_min_seen = math.inf
        h_max_seen = 0.0
    else:
        t = at[P_T]
        h = at[P_H]
        io = int(at[P_IO])
        k_first = n_int if phase == PH_END else int(at[P_PIECE])
        n_steps = int(at[P_STEPS])
        n_rej = int(at[P_REJECTED])
        n_ev = int(at[P_EVENTS])
        n_fev = int(at[P_FEV])
        n_start = int(at[P_START_FLIPS])
        h_min_seen = at[P_HMIN]
        h_max_seen = at[P_HMAX]
    exponent = -1.0 / 8.0

    for k in range(k_first, n_int):
        tb = brk[k + 1]
        if not (phase == PH_STEP and k == k_first):  # (a call that goes on within piece k has its f)
            if lim < n_out and t_out[lim - 1 - io0] <= t:
                # the rows at the piece's start may run past those at hand
                _pause(at, info, PH_PIECE, t, h, k, io, n_steps, n_rej, n_ev, n_fev, n_start, h_min_seen, h_max_seen)
                return io
            bad = _rhs(t, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, f)
            n_fev += 1
            if bad >= 0:
                info[R_STATUS] = ST_OVERFLOW
                info[R_ELEMENT] = bad
                info[R_TIME] = t
                return io
            if io < lim and t_out[io - io0] <= t:
                # outputs at the start (t = 0) come from the state itself
                while io < lim and t_out[io - io0] <= t:
                    for i in range(ny):
                        yo[i] = y[i]
                    io = _write(io - io0, yo, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
        while tb - t > 1e-13 * max(1.0, abs(tb)):
            if n_steps + n_rej > max_steps:
                info[R_STATUS] = ST_TOO_MANY_STEPS
                info[R_TIME] = t
                return io
            hh = h
            if t + hh >= tb - 1e-13 * max(1.0, abs(tb)):
                hh = tb - t
            if lim < n_out and t_out[lim - 1 - io0] <= t + hh + 1e-12 * max(1.0, abs(t + hh)):
                # this step may write rows past those at hand: the next call takes it
                _pause(at, info, PH_STEP, t, h, k, io, n_steps, n_rej, n_ev, n_fev, n_start, h_min_seen, h_max_seen)
                return io
            if hh < 1e-14 * max(1.0, abs(t)):
                info[R_STATUS] = ST_STEP_TOO_SMALL
                info[R_TIME] = t
                return io
            # ---- one DOP853 step
            for i in range(ny):
                K[0, i] = f[i]
            bad = _stages(1, 12, t, hh, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, A, C, K, ytmp)
            n_fev += 11
            if bad < 0:
                for i in range(ny):
                    acc = 0.0
                    for j in range(12):
                        acc += B[j] * K[j, i]
                    y_new[i] = y[i] + hh * acc
                bad = _rhs(t + hh, y_new, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, f_new)
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
            for i in range(ny):
                K[12, i] = f_new[i]
            err5 = 0.0
            err3 = 0.0
            for i in range(nerr):
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
                err = hh * err5 / math.sqrt((err5 + 0.01 * err3) * nerr)
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
                g0 = s[e] * _v_el(bvec, axial, rot, e, y, n)
                g1 = s[e] * _v_el(bvec, axial, rot, e, y_new, n)
                if g1 < 0.0:
                    need = True
                    break
                # cubic Hermite of g over the step, from g and g' at both ends
                d0 = hh * s[e] * _a_el(bvec, axial, rot, e, y, f, n)
                d1 = hh * s[e] * _a_el(bvec, axial, rot, e, y_new, f_new, n)
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
                _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params,
                                    cm, s, up, gp, ms, p, A, C, D, K, F, ytmp)
                n_fev += 3
                have_dense = True
                for e in range(ne):
                    xroot[e] = 2.0
                    se = s[e]
                    gs[0] = se * _v_el(bvec, axial, rot, e, y, n)
                    gs[NS] = se * _v_el(bvec, axial, rot, e, y_new, n)
                    for m in range(1, NS):
                        gs[m] = _g_dense(F, y, m / NS, bvec, axial, rot, e, se, n)
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
                        gm = _g_dense(F, y, xm, bvec, axial, rot, e, se, n)
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
                        _new_branch(e, y, bvec, axial, rot, params, s, up, gp, ap, wacc, n)
                        n_start += 1
                bad = _rhs(t, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, f)
                n_fev += 1
                if n_start > 100 * (n_ev + n_steps + 10):
                    info[R_STATUS] = ST_STEP_TOO_SMALL
                    info[R_TIME] = t
                    return io
                continue
            if ev >= 0:
                t_ev = t + x_ev * hh
                # outputs before the reversal from this step's dense output
                while io < lim and t_out[io - io0] < t_ev:
                    x = (t_out[io - io0] - t) / hh
                    for i in range(ny):
                        yo[i] = _dense(F, y, x, i)
                    io = _write(io - io0, yo, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
                # the state at the reversal from the step's dense output (7th order, within the
                # step's tolerance: the step was accepted), not from the step redone to it
                h_ev = t_ev - t
                for i in range(ny):
                    y_ev[i] = _dense(F, y, x_ev, i) if h_ev > 0.0 else y[i]
                t = t_ev
                for i in range(ny):
                    y[i] = y_ev[i]
                _stops_at(y, bvec, axial, rot, params, ms, n)
                while io < lim and t_out[io - io0] <= t:
                    io = _write(io - io0, y, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
                # elements that reverse together (identical b and sets, or by chance within
                # SIMULTANEOUS of the step) all start their new branches here
                for e in range(ne):
                    if xroot[e] <= x_ev + SIMULTANEOUS:
                        _new_branch(e, y, bvec, axial, rot, params, s, up, gp, ap, wacc, n)
                        n_ev += 1
                n_steps += 1
                bad = _rhs(t, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, f)
                n_fev += 1
                if h_ev > 0.0:
                    h_min_seen = min(h_min_seen, h_ev)
                continue
            # ---- accept the whole step
            while io < lim and t_out[io - io0] < t + hh:
                if not have_dense:
                    _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params,
                                        cm, s, up, gp, ms, p, A, C, D, K, F, ytmp)
                    n_fev += 3
                    have_dense = True
                x = (t_out[io - io0] - t) / hh
                for i in range(ny):
                    yo[i] = _dense(F, y, x, i)
                io = _write(io - io0, yo, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
            clipped = hh < h
            t = tb if hh == tb - t else t + hh
            for i in range(ny):
                y[i] = y_new[i]
                f[i] = f_new[i]
            _stops_at(y, bvec, axial, rot, params, ms, n)
            n_steps += 1
            h_min_seen = min(h_min_seen, hh)
            h_max_seen = max(h_max_seen, hh)
            h = max(h, hh * factor) if clipped else hh * factor
            while io < lim and t_out[io - io0] <= t:
                io = _write(io - io0, y, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
            finite = True
            for i in range(n):
                finite = finite and math.isfinite(y[i])
            if not finite:
                info[R_STATUS] = ST_NONFINITE
                info[R_TIME] = t
                return io
    # outputs left by round-off at the very end
    while io < n_out:
        if io >= lim:
            _pause(at, info, PH_END, t, h, n_int, io, n_steps, n_rej, n_ev, n_fev, n_start, h_min_seen, h_max_seen)
            return io
        io = _write(io - io0, y, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n) + io0
    info[R_STATUS] = ST_OK
    info[R_STEPS] = n_steps
    info[R_REJECTED] = n_rej
    info[R_EVENTS] = n_ev
    info[R_FEV] = n_fev
    info[R_HMIN] = h_min_seen
    info[R_HMAX] = h_max_seen
    info[R_START_FLIPS] = n_start
    return io


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _pause(at, info, phase, t, h, k, io, n_steps, n_rej, n_ev, n_fev, n_start, h_min_seen, h_max_seen):
    """Where a call of _integrate stopped, for the next to go on from (dop853_layout: P_*)."""
    at[P_PHASE] = phase
    at[P_T] = t
    at[P_H] = h
    at[P_PIECE] = k
    at[P_IO] = io
    at[P_STEPS] = n_steps
    at[P_REJECTED] = n_rej
    at[P_EVENTS] = n_ev
    at[P_FEV] = n_fev
    at[P_START_FLIPS] = n_start
    at[P_HMIN] = h_min_seen
    at[P_HMAX] = h_max_seen
    info[R_STATUS] = ST_PAUSED
    info[R_TIME] = t


@njit(cache=True, error_model="numpy", _nrt=False)
def _stages(first, last, t, hh, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, A, C, K, ytmp):
    """Runge-Kutta stages first..last-1 of a step hh from (t, y) into the rows of K;
    returns the first element whose exponential overflowed, or -1."""
    for st in range(first, last):
        for i in range(2 * len(minv) + 2):
            acc = 0.0
            for j in range(st):
                acc += A[st, j] * K[j, i]
            ytmp[i] = y[i] + hh * acc
        bad = _rhs(t + C[st] * hh, ytmp, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, K[st])
        if bad >= 0:
            return bad
    return -1


@njit(cache=True, error_model="numpy", _nrt=False)
def _dense_coefficients(t, hh, y, y_new, f, f_new, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p,
                        A, C, D, K, F, ytmp):
    """The three extra stages and the 7 rows of DOP853's dense output (as scipy's DOP853)."""
    _stages(13, 16, t, hh, y, k, brk, pcoef, sig, minv, bvec, axial, rot, mult, params, cm, s, up, gp, ms, p, A, C, K, ytmp)
    for i in range(2 * len(minv) + 2):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = hh * f[i] - dy
        F[2, i] = 2.0 * dy - hh * (f_new[i] + f[i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = hh * acc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _new_branch(e, y, bvec, axial, rot, params, s, up, gp, ap, wacc, n):
    """Element e reverses at the current state: a new branch from the force it has (eq. 14)."""
    u = _u_el(bvec, axial, rot, e, y, n)
    f_old, big_old, _ = _force(params, e, s[e], up[e], gp[e], u)
    alpha = params[e, branch_row(s[e]), ALPHA]
    wacc[e] += big_old - ap[e] + s[e] * gp[e] * (math.exp(-s[e] * alpha * (u - up[e])) - 1.0) / alpha
    s[e] = -s[e]
    row = branch_row(s[e])
    c, kc, big, ok = branch_eval(params, e, row, s[e], u)
    up[e] = u
    gp[e] = c - f_old
    ap[e] = big


@njit(cache=True, error_model="numpy", _nrt=False)
def _write(io, y, bvec, axial, rot, mult, params, s, up, gp, ap, wacc, ms, out_y, out_eu, out_ef, out_eh, n):
    """One output row from the state y on the current branches: the state, each element row's
    deformation and force (its stop's with it), the hysteretic work (the stops' with it)."""
    eh = 0.0
    stops = params.shape[1] > STOP_ROW
    for e in range(bvec.shape[0]):
        u = _u_el(bvec, axial, rot, e, y, n)
        fe, big, _ = _force(params, e, s[e], up[e], gp[e], u)
        alpha = params[e, branch_row(s[e]), ALPHA]
        w = wacc[e] + big - ap[e] + s[e] * gp[e] * (math.exp(-s[e] * alpha * (u - up[e])) - 1.0) / alpha
        if stops:
            fs, ws = stop_force(params, e, u, ms[0, e], ms[1, e])
            if fs != 0.0:
                fe += fs
            w += ms[2, e] + ws - ms[6, e]
        out_eu[io, e] = u
        out_ef[io, e] = fe
        eh += mult[e] * w
    for i in range(2 * n + 2):
        out_y[io, i] = y[i]
    out_eh[io] = eh
    return io + 1


@njit(cache=True, error_model="numpy", _nrt=False)
def _stops_at(y, bvec, axial, rot, params, ms, n):
    """The stops at a state the integration reached (a step's end, an event: along each step the
    deformation is monotonic, its turns being events, so a contact's peak is the larger of the held
    one and the deformation now). ms (6, ne): each side's held peak (lower, upper), the energy
    finished contacts lost, contacts begun, the largest force and penetration."""
    if params.shape[1] <= STOP_ROW:
        return
    for e in range(bvec.shape[0]):
        k = params[e, STOP_ROW, STOP_K]
        if k == 0.0:
            continue
        r = params[e, STOP_ROW, STOP_E]
        u = _u_el(bvec, axial, rot, e, y, n)
        fs, _ = stop_force(params, e, u, ms[0, e], ms[1, e])
        for side in range(2):
            d = u - params[e, STOP_ROW, STOP_UPPER] if side == 1 else params[e, STOP_ROW, STOP_LOWER] - u
            m0 = ms[side, e]
            if d > 0.0:
                if m0 == 0.0:
                    ms[3, e] += 1.0
                ms[side, e] = max(m0, d)
                ms[5, e] = max(ms[5, e], ms[side, e])
            elif m0 != 0.0:  # back past the gap: the contact is over, its loss kept
                ms[2, e] += 0.5 * k * (1.0 - r * r) * m0 * m0
                ms[side, e] = 0.0
        ms[4, e] = max(ms[4, e], abs(fs))
