"""Compiled time-stepping loop: arrays and floats in, preallocated buffers out.

One loop serves every fixed-step integrator; a method is an integer id and a
stack of 3x3 coefficient matrices per substep level (built in
:mod:`rbhyst.integrators`). Each step is checked against the stiffest mode it
has to resolve: the loop halves the step (the load interpolated linearly) until
``omega_max * h <= omega_dt_limit`` or the substep level runs out.

Everything here is called through :func:`rbhyst.simulate.simulate`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .hysteresis import virgin_tangent, vrm_update

# method ids (see integrators/__init__.py)
CHANG = 0
CENTRAL_DIFFERENCE = 1
NEWMARK = 2  # average acceleration, implicit: Newton iterations with the VRM tangent
KR_ALPHA = 3  # Kolay-Ricles alpha family, explicit

# status codes written to info[0]
OK = 0
UNRESOLVED = 1  # the stiffness needs more substeps than allowed
OVERFLOW = 2  # an element left its calibrated range (exp overflow)
NONFINITE = 3  # a NaN or Inf appeared in the state
NOT_CONVERGED = 4  # Newton iterations failed even at the finest substep level

#: "bad element" a step returns when its Newton iterations did not converge:
#: the loop retries the compute step with twice the substeps
NEWTON_FAILED = -2

# element state columns: displacement, force, branch sign, gap, tangent, antiderivative
U, F, S, G, K, A = range(6)
N_STATE = 6

# info layout
I_STATUS, I_ELEMENT, I_TIME, I_STIFFNESS, I_OMEGA, I_SUBSTEPS, I_LEVEL, I_OMEGA_DT, I_STEPS, I_ITER = range(10)
INFO_SIZE = 10  # I_STEPS: substeps taken in all; I_ITER: Newton iterations in all (newmark)


@njit(cache=True, error_model="numpy")
def sym3_max_eig(a11, a22, a33, a12, a13, a23):
    """Largest eigenvalue of a symmetric 3x3 matrix (trigonometric closed form)."""
    p1 = a12 * a12 + a13 * a13 + a23 * a23
    q = (a11 + a22 + a33) / 3.0
    if p1 <= 1e-30 * (a11 * a11 + a22 * a22 + a33 * a33):
        return max(a11, max(a22, a33))
    b11 = a11 - q
    b22 = a22 - q
    b33 = a33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    det = b11 * (b22 * b33 - a23 * a23) - a12 * (a12 * b33 - a23 * a13) + a13 * (a12 * a23 - b22 * a13)
    r = det / (2.0 * p * p * p)
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    return q + 2.0 * p * math.cos(phi)


@njit(cache=True, error_model="numpy", inline="always")
def update_elements(bvec, mult, params, q, es, en, kpeak, r):
    """Elements at the new configuration q (eqs. 5-11).

    es: (ne, 6) element state at the start of the step (columns U, F, S, G, K, A,
    see hysteresis.vrm_update); en receives the new state, kpeak the largest
    tangent over the step, r the restoring force sum mult b f.
    Returns (ok, bad element, work of all element forces over the step).
    """
    r[0] = 0.0
    r[1] = 0.0
    r[2] = 0.0
    work = 0.0
    for e in range(bvec.shape[0]):
        b0 = bvec[e, 0]
        b1 = bvec[e, 1]
        b2 = bvec[e, 2]
        u = b0 * q[0] + b1 * q[1] + b2 * q[2]
        f, s, g, k, a, kstart, w, ok = vrm_update(params, e, es[e, U], es[e, F], es[e, S], es[e, G],
                                                  es[e, K], es[e, A], u)
        if not ok:
            return False, e, work
        en[e, U] = u
        en[e, F] = f
        en[e, S] = s
        en[e, G] = g
        en[e, K] = k
        en[e, A] = a
        kpeak[e] = max(kstart, k)
        m = mult[e]
        work += m * w
        r[0] += m * b0 * f
        r[1] += m * b1 * f
        r[2] += m * b2 * f
    return True, -1, work


@njit(cache=True, error_model="numpy", inline="always")
def omega_squared(bvec, mult, kpeak, wgt):
    """Trace bound on omega_max^2 = max eig(M^-1 K), K = sum mult k b b^T (k >= 0).

    Returns the bound and the element with the largest share of it; the exact
    eigenvalue (omega_squared_exact) is computed only when the bound is too high.
    """
    trace = 0.0
    worst = 0
    share = -1.0
    for e in range(bvec.shape[0]):
        c = mult[e] * max(kpeak[e], 0.0) * wgt[e]
        trace += c
        if c > share:
            share = c
            worst = e
    return trace, worst


@njit(cache=True, error_model="numpy")
def omega_squared_exact(bvec, mult, minv, kpeak):
    """max eig(M^-1/2 K M^-1/2), the exact omega_max^2 of the tangent system."""
    s11 = s22 = s33 = s12 = s13 = s23 = 0.0
    for e in range(bvec.shape[0]):
        k = mult[e] * max(kpeak[e], 0.0)
        if k == 0.0:
            continue
        x = bvec[e, 0] * math.sqrt(minv[0])
        y = bvec[e, 1] * math.sqrt(minv[1])
        z = bvec[e, 2] * math.sqrt(minv[2])
        s11 += k * x * x
        s22 += k * y * y
        s33 += k * z * z
        s12 += k * x * y
        s13 += k * x * z
        s23 += k * y * z
    return sym3_max_eig(s11, s22, s33, s12, s13, s23)


@njit(cache=True, error_model="numpy")
def _matvec(A, x, out):
    for i in range(3):
        out[i] = A[i, 0] * x[0] + A[i, 1] * x[1] + A[i, 2] * x[2]


@njit(cache=True, error_model="numpy", inline="always")
def step_newmark_explicit(coef, lv, minv, bvec, mult, params, d, v, a, p1, h, es, en, kpeak, d1, v1, a1, r):
    """One step of Chang's explicit method (coef[lv, 0] = B1, coef[lv, 1] = B2) or of
    central difference (B1 = I, B2 = I/2):

        d+ = d + h B1 v + h^2 B2 a,  M a+ = p+ - R(d+),  v+ = v + h/2 (a + a+).

    Returns (ok, bad element, element work over the step).
    """
    hh = h * h
    for i in range(3):
        d1[i] = (d[i] + h * (coef[lv, 0, i, 0] * v[0] + coef[lv, 0, i, 1] * v[1] + coef[lv, 0, i, 2] * v[2])
                 + hh * (coef[lv, 1, i, 0] * a[0] + coef[lv, 1, i, 1] * a[1] + coef[lv, 1, i, 2] * a[2]))
    ok, bad, work = update_elements(bvec, mult, params, d1, es, en, kpeak, r)
    if not ok:
        return False, bad, 0.0
    for i in range(3):
        a1[i] = minv[i] * (p1[i] - r[i])
        v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
    return True, -1, work


@njit(cache=True, error_model="numpy", inline="always")
def _copy2(src, dst):
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True, error_model="numpy")
def _fail(info, status, element, t, substeps, level):
    info[I_STATUS] = status
    info[I_ELEMENT] = element
    info[I_TIME] = t
    info[I_SUBSTEPS] = substeps
    info[I_LEVEL] = level


@njit(cache=True, error_model="numpy")
def run(method, coef, minv, bvec, mult, params, load, h_c, nsub_c, n_steps, every,
        omega_dt_limit, min_level, max_level, d, v, a,
        out_d, out_v, out_a, out_u, out_f, out_e, info):
    """Integrate from the state (d, v, a) at t = 0 over n_steps output steps.

    load: (n_steps * nsub_c + 1, 3) generalized load on the compute grid of step h_c.
    out_*: rows at every ``every``-th output step, row 0 being t = 0.
    out_e columns: input energy, kinetic energy, hysteretic work (cumulative).
    Every compute step is split into at least 2**min_level substeps (a structure-
    dependent method needs omega_0 h within the limit too, see simulate.min_level).
    Returns the number of rows written after row 0; info tells how it ended.
    """
    ne = bvec.shape[0]
    mass = 1.0 / minv
    wgt = np.empty(ne)
    for e in range(ne):
        wgt[e] = bvec[e, 0] ** 2 * minv[0] + bvec[e, 1] ** 2 * minv[1] + bvec[e, 2] ** 2 * minv[2]
    # virgin elements: u = f = 0 and no branch yet (S = 0), so the first move
    # starts a branch whatever its direction; until it moves, an element's tangent
    # is the stiffer of its two first moves, so the monitor sees a stiff body at
    # rest before the first step that moves it (a zero start moves nothing)
    es = np.zeros((ne, N_STATE))
    for e in range(ne):
        es[e, K] = max(virgin_tangent(params[e], 1.0), virgin_tangent(params[e], -1.0))
    en = np.zeros((ne, N_STATE))
    es_save = np.zeros((ne, N_STATE))
    kpeak = np.empty(ne)
    d1 = np.empty(3)
    v1 = np.empty(3)
    a1 = np.empty(3)
    r = np.zeros(3)
    p0 = np.empty(3)
    p1 = np.empty(3)
    d_save = np.empty(3)
    v_save = np.empty(3)
    a_save = np.empty(3)

    e_in = 0.0
    e_hyst = 0.0
    substeps = 0
    level_used = 0
    level = 0
    omega_dt_seen = 0.0
    row = 0
    limit2 = omega_dt_limit * omega_dt_limit

    for i in range(3):
        out_d[0, i] = d[i]
        out_v[0, i] = v[i]
        out_a[0, i] = a[i]
    out_e[0, 1] = 0.5 * (mass[0] * v[0] ** 2 + mass[1] * v[1] ** 2 + mass[2] * v[2] ** 2)

    per_row = nsub_c * every
    for j in range(n_steps * nsub_c):
        # keep the state to restart this compute step if a substep is rejected
        for i in range(3):
            d_save[i] = d[i]
            v_save[i] = v[i]
            a_save[i] = a[i]
        _copy2(es, es_save)
        e_in_save = e_in
        e_hyst_save = e_hyst
        level = max(level - 1, min_level)
        while True:
            nsub = 1 << level
            inv_nsub = 1.0 / nsub
            h = h_c * inv_nsub
            accepted = True
            for k in range(nsub):
                # load at the ends of the substep, linear within the compute step
                w0 = k * inv_nsub
                w1 = (k + 1) * inv_nsub
                for i in range(3):
                    p0[i] = load[j, i] + w0 * (load[j + 1, i] - load[j, i])
                    p1[i] = load[j, i] + w1 * (load[j + 1, i] - load[j, i])
                if method == CHANG or method == CENTRAL_DIFFERENCE:
                    ok, bad, work = step_newmark_explicit(coef, level, minv, bvec, mult, params, d, v, a, p1, h,
                                                          es, en, kpeak, d1, v1, a1, r)
                else:
                    ok, bad, work = False, -1, 0.0
                t_now = (j + w1) * h_c
                if not ok:
                    _fail(info, OVERFLOW if bad >= 0 else NONFINITE, bad, t_now, substeps, level_used)
                    return row
                # resolution check on the stiffest instantaneous mode of the step
                lam, worst = omega_squared(bvec, mult, kpeak, wgt)
                if lam * h * h > limit2:
                    lam = omega_squared_exact(bvec, mult, minv, kpeak)
                    if lam * h * h > limit2:
                        if level >= max_level:
                            _fail(info, UNRESOLVED, worst, t_now, substeps, level_used)
                            info[I_STIFFNESS] = kpeak[worst]
                            info[I_OMEGA] = math.sqrt(lam)
                            return row
                        accepted = False
                        break
                omega_dt = math.sqrt(max(lam, 0.0)) * h
                if omega_dt > omega_dt_seen:
                    omega_dt_seen = omega_dt
                for i in range(3):
                    e_in += 0.5 * (p0[i] + p1[i]) * (d1[i] - d[i])
                    d[i] = d1[i]
                    v[i] = v1[i]
                    a[i] = a1[i]
                e_hyst += work
                _copy2(en, es)
            if accepted:
                if level > 0:
                    substeps += nsub
                    level_used = max(level_used, level)
                break
            # restart the compute step with twice as many substeps
            for i in range(3):
                d[i] = d_save[i]
                v[i] = v_save[i]
                a[i] = a_save[i]
            _copy2(es_save, es)
            e_in = e_in_save
            e_hyst = e_hyst_save
            level += 1

        if not (math.isfinite(d[0]) and math.isfinite(d[1]) and math.isfinite(d[2])
                and math.isfinite(a[0]) and math.isfinite(a[1]) and math.isfinite(a[2])):
            _fail(info, NONFINITE, -1, (j + 1) * h_c, substeps, level_used)
            return row

        if (j + 1) % per_row == 0:
            row += 1
            for i in range(3):
                out_d[row, i] = d[i]
                out_v[row, i] = v[i]
                out_a[row, i] = a[i]
            for e in range(ne):
                out_u[row, e] = es[e, U]
                out_f[row, e] = es[e, F]
            out_e[row, 0] = e_in
            out_e[row, 1] = 0.5 * (mass[0] * v[0] ** 2 + mass[1] * v[1] ** 2 + mass[2] * v[2] ** 2)
            out_e[row, 2] = e_hyst

    info[I_STATUS] = OK
    info[I_SUBSTEPS] = substeps
    info[I_LEVEL] = level_used
    info[I_OMEGA_DT] = omega_dt_seen
    return row
