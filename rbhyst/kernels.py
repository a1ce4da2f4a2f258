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

from .hysteresis import vrm_update

# method ids (see integrators/__init__.py)
CHANG = 0
CENTRAL_DIFFERENCE = 1

# status codes written to info[0]
OK = 0
UNRESOLVED = 1  # the stiffness needs more substeps than allowed
OVERFLOW = 2  # an element left its calibrated range (exp overflow)
NONFINITE = 3  # a NaN or Inf appeared in the state

# info layout
I_STATUS, I_ELEMENT, I_TIME, I_STIFFNESS, I_OMEGA, I_SUBSTEPS, I_LEVEL, I_OMEGA_DT = range(8)
INFO_SIZE = 8


@njit(cache=True)
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


@njit(cache=True)
def update_elements(bvec, mult, params, q, ue, fe, se, ge, ke, un, fn, sn, gn, kn, kpeak, r):
    """Elements at the new configuration q (eqs. 5-11): fills the new element state,
    the peak tangent over the step (kpeak) and the restoring force r = sum b f.

    Returns (ok, bad element, work of all element forces over the step).
    """
    r[0] = 0.0
    r[1] = 0.0
    r[2] = 0.0
    work = 0.0
    for e in range(bvec.shape[0]):
        b = bvec[e]
        u = b[0] * q[0] + b[1] * q[1] + b[2] * q[2]
        f, s, g, k, kstart, w, ok = vrm_update(params[e], ue[e], fe[e], se[e], ge[e], ke[e], u)
        if not ok:
            return False, e, work
        un[e] = u
        fn[e] = f
        sn[e] = s
        gn[e] = g
        kn[e] = k
        kpeak[e] = max(kstart, k)
        m = mult[e]
        work += m * w
        r[0] += m * b[0] * f
        r[1] += m * b[1] * f
        r[2] += m * b[2] * f
    return True, -1, work


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def _matvec(A, x, out):
    for i in range(3):
        out[i] = A[i, 0] * x[0] + A[i, 1] * x[1] + A[i, 2] * x[2]


@njit(cache=True)
def step_newmark_explicit(coef, minv, bvec, mult, params, d, v, a, p1, h,
                          ue, fe, se, ge, ke, un, fn, sn, gn, kn, kpeak, d1, v1, a1, r, tmp):
    """Chang's explicit method (coef[0] = B1, coef[1] = B2) or central difference
    (B1 = I, B2 = I/2):

        d+ = d + h B1 v + h^2 B2 a,  M a+ = p+ - R(d+),  v+ = v + h/2 (a + a+).
    """
    _matvec(coef[0], v, tmp)
    for i in range(3):
        d1[i] = d[i] + h * tmp[i]
    _matvec(coef[1], a, tmp)
    for i in range(3):
        d1[i] += h * h * tmp[i]
    ok, bad, work = update_elements(bvec, mult, params, d1, ue, fe, se, ge, ke, un, fn, sn, gn, kn, kpeak, r)
    if not ok:
        return False, bad, 0.0
    for i in range(3):
        a1[i] = minv[i] * (p1[i] - r[i])
        v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
    return True, -1, work


@njit(cache=True)
def run(method, coef, minv, bvec, mult, params, load, h_c, nsub_c, n_steps, every,
        omega_dt_limit, max_level, d, v, a,
        out_d, out_v, out_a, out_u, out_f, out_e, info):
    """Integrate from the state (d, v, a) at t = 0 over n_steps output steps.

    load: (n_steps * nsub_c + 1, 3) generalized load on the compute grid of step h_c.
    out_*: rows at every ``every``-th output step, row 0 being t = 0.
    out_e columns: input energy, kinetic energy, hysteretic work (cumulative).
    """
    ne = bvec.shape[0]
    mass = 1.0 / minv
    wgt = np.empty(ne)
    for e in range(ne):
        wgt[e] = bvec[e, 0] ** 2 * minv[0] + bvec[e, 1] ** 2 * minv[1] + bvec[e, 2] ** 2 * minv[2]
    # virgin elements: u = f = 0 and no branch yet (s = 0), so the first move
    # starts a branch whatever its direction
    ue = np.zeros(ne)
    fe = np.zeros(ne)
    se = np.zeros(ne)
    ge = np.zeros(ne)
    ke = np.zeros(ne)
    un = np.empty(ne)
    fn = np.empty(ne)
    sn = np.empty(ne)
    gn = np.empty(ne)
    kn = np.empty(ne)
    kpeak = np.empty(ne)
    d1 = np.empty(3)
    v1 = np.empty(3)
    a1 = np.empty(3)
    r = np.zeros(3)
    tmp = np.empty(3)
    p0 = np.empty(3)
    p1 = np.empty(3)
    # state at the start of the compute step, to restart it with smaller substeps
    d_s = np.empty(3)
    v_s = np.empty(3)
    a_s = np.empty(3)
    ue_s = np.empty(ne)
    fe_s = np.empty(ne)
    se_s = np.empty(ne)
    ge_s = np.empty(ne)
    ke_s = np.empty(ne)

    e_in = 0.0
    e_hyst = 0.0
    substeps = 0
    level_used = 0
    level = 0
    omega_dt_seen = 0.0
    row = 0

    # row 0: the initial state
    for i in range(3):
        out_d[0, i] = d[i]
        out_v[0, i] = v[i]
        out_a[0, i] = a[i]
    for e in range(ne):
        out_u[0, e] = 0.0
        out_f[0, e] = 0.0
    out_e[0, 0] = 0.0
    out_e[0, 1] = 0.5 * (mass[0] * v[0] ** 2 + mass[1] * v[1] ** 2 + mass[2] * v[2] ** 2)
    out_e[0, 2] = 0.0

    n_compute = n_steps * nsub_c
    per_row = nsub_c * every
    for j in range(n_compute):
        # save the state to restart this compute step if a substep is rejected
        for i in range(3):
            d_s[i] = d[i]
            v_s[i] = v[i]
            a_s[i] = a[i]
        for e in range(ne):
            ue_s[e] = ue[e]
            fe_s[e] = fe[e]
            se_s[e] = se[e]
            ge_s[e] = ge[e]
            ke_s[e] = ke[e]
        e_in_s = e_in
        e_hyst_s = e_hyst
        level = max(level - 1, 0)
        while True:
            nsub = 1 << level
            h = h_c / nsub
            cl = coef[level]
            accepted = True
            for k in range(nsub):
                # load at both ends of the substep, linear within the compute step
                w0 = k / nsub
                w1 = (k + 1) / nsub
                for i in range(3):
                    p0[i] = (1.0 - w0) * load[j, i] + w0 * load[j + 1, i]
                    p1[i] = (1.0 - w1) * load[j, i] + w1 * load[j + 1, i]
                if method == CHANG or method == CENTRAL_DIFFERENCE:
                    ok, bad, work = step_newmark_explicit(
                        cl, minv, bvec, mult, params, d, v, a, p1, h,
                        ue, fe, se, ge, ke, un, fn, sn, gn, kn, kpeak, d1, v1, a1, r, tmp)
                else:
                    ok, bad, work = False, -2, 0.0
                t_now = (j + w1) * h_c
                if not ok:
                    info[I_STATUS] = OVERFLOW if bad >= 0 else NONFINITE
                    info[I_ELEMENT] = bad
                    info[I_TIME] = t_now
                    info[I_SUBSTEPS] = substeps
                    info[I_LEVEL] = level_used
                    return row
                lam, worst = omega_squared(bvec, mult, kpeak, wgt)
                if lam * h * h > omega_dt_limit * omega_dt_limit:
                    lam = omega_squared_exact(bvec, mult, minv, kpeak)
                omega_dt = math.sqrt(max(lam, 0.0)) * h
                if omega_dt > omega_dt_limit:
                    if level >= max_level:
                        info[I_STATUS] = UNRESOLVED
                        info[I_ELEMENT] = worst
                        info[I_TIME] = t_now
                        info[I_STIFFNESS] = kpeak[worst]
                        info[I_OMEGA] = math.sqrt(lam)
                        info[I_SUBSTEPS] = substeps
                        info[I_LEVEL] = level_used
                        return row
                    accepted = False
                    break
                if omega_dt > omega_dt_seen:
                    omega_dt_seen = omega_dt
                # accept the substep
                for i in range(3):
                    e_in += 0.5 * (p0[i] + p1[i]) * (d1[i] - d[i])
                    d[i] = d1[i]
                    v[i] = v1[i]
                    a[i] = a1[i]
                e_hyst += work
                for e in range(ne):
                    ue[e] = un[e]
                    fe[e] = fn[e]
                    se[e] = sn[e]
                    ge[e] = gn[e]
                    ke[e] = kn[e]
            if accepted:
                if level > 0:
                    substeps += nsub
                    if level > level_used:
                        level_used = level
                break
            # restart the compute step with twice as many substeps
            for i in range(3):
                d[i] = d_s[i]
                v[i] = v_s[i]
                a[i] = a_s[i]
            for e in range(ne):
                ue[e] = ue_s[e]
                fe[e] = fe_s[e]
                se[e] = se_s[e]
                ge[e] = ge_s[e]
                ke[e] = ke_s[e]
            e_in = e_in_s
            e_hyst = e_hyst_s
            level += 1

        if not (math.isfinite(d[0]) and math.isfinite(d[1]) and math.isfinite(d[2])
                and math.isfinite(a[0]) and math.isfinite(a[1]) and math.isfinite(a[2])):
            info[I_STATUS] = NONFINITE
            info[I_ELEMENT] = -1
            info[I_TIME] = (j + 1) * h_c
            info[I_SUBSTEPS] = substeps
            info[I_LEVEL] = level_used
            return row

        if (j + 1) % per_row == 0:
            row += 1
            for i in range(3):
                out_d[row, i] = d[i]
                out_v[row, i] = v[i]
                out_a[row, i] = a[i]
            for e in range(ne):
                out_u[row, e] = ue[e]
                out_f[row, e] = fe[e]
            out_e[row, 0] = e_in
            out_e[row, 1] = 0.5 * (mass[0] * v[0] ** 2 + mass[1] * v[1] ** 2 + mass[2] * v[2] ** 2)
            out_e[row, 2] = e_hyst

    info[I_STATUS] = OK
    info[I_SUBSTEPS] = substeps
    info[I_LEVEL] = level_used
    info[I_OMEGA_DT] = omega_dt_seen
    return row
