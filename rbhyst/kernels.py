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

#: (8 eps)^2: a Newton correction below 8 ulps of d+ is converged whatever the increment
ROUNDOFF2 = (8.0 * 2.220446049250313e-16) ** 2

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


@njit(cache=True, error_model="numpy", inline="always")
def bbt_sums(bvec, mult, k, minv, normalized):
    """The six entries (11, 22, 33, 12, 13, 23) of K = sum mult k_e b_e b_e^T, or where
    ``normalized`` of M^-1/2 K M^-1/2 with negative k_e taken as 0 (for omega_max^2)."""
    s11 = s22 = s33 = s12 = s13 = s23 = 0.0
    q0 = math.sqrt(minv[0]) if normalized else 1.0
    q1 = math.sqrt(minv[1]) if normalized else 1.0
    q2 = math.sqrt(minv[2]) if normalized else 1.0
    for e in range(bvec.shape[0]):
        ke = mult[e] * (max(k[e], 0.0) if normalized else k[e])
        if ke == 0.0:
            continue
        x = bvec[e, 0] * q0
        y = bvec[e, 1] * q1
        z = bvec[e, 2] * q2
        s11 += ke * x * x
        s22 += ke * y * y
        s33 += ke * z * z
        s12 += ke * x * y
        s13 += ke * x * z
        s23 += ke * y * z
    return s11, s22, s33, s12, s13, s23


@njit(cache=True, error_model="numpy")
def omega_squared_exact(bvec, mult, minv, kpeak):
    """max eig(M^-1/2 K M^-1/2), the exact omega_max^2 of the tangent system."""
    s11, s22, s33, s12, s13, s23 = bbt_sums(bvec, mult, kpeak, minv, True)
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
def step_kr_alpha(coef, lv, minv, bvec, mult, params, d, v, a, p0, p1, h, es, en, kpeak, d1, v1, a1, r):
    """One step of the KR-alpha method (Kolay and Ricles 2014), v being the velocity at t:

        d+ = d + h v + h^2 C1 a
        M (I - A3) a+ = p(t+ - af) - R(+ - af) - M A3 a,  x(+ - af) = (1 - af) x+ + af x
        v+ = v + h C0 a + h gamma a+

    coef[lv]: 0 = A1 - gamma I, 1 = A2 - gamma I, 2 = Mh^-1 M A3, 3 = (1 - af) Mh^-1,
    4 = af Mh^-1, 5 = gamma I, Mh = M (I - A3) (see integrators/kr_alpha.py). ``a`` is
    the method's own acceleration variable; R at the start of the step comes from es.
    Returns (ok, bad element, element work over the step).
    """
    rn0 = 0.0
    rn1 = 0.0
    rn2 = 0.0
    for e in range(bvec.shape[0]):
        mf = mult[e] * es[e, F]
        rn0 += mf * bvec[e, 0]
        rn1 += mf * bvec[e, 1]
        rn2 += mf * bvec[e, 2]
    hh = h * h
    for i in range(3):
        d1[i] = d[i] + h * v[i] + hh * (coef[lv, 1, i, 0] * a[0] + coef[lv, 1, i, 1] * a[1]
                                        + coef[lv, 1, i, 2] * a[2])
    ok, bad, work = update_elements(bvec, mult, params, d1, es, en, kpeak, r)
    if not ok:
        return False, bad, 0.0
    x0 = p1[0] - r[0]
    x1 = p1[1] - r[1]
    x2 = p1[2] - r[2]
    y0 = p0[0] - rn0
    y1 = p0[1] - rn1
    y2 = p0[2] - rn2
    for i in range(3):
        a1[i] = (coef[lv, 3, i, 0] * x0 + coef[lv, 3, i, 1] * x1 + coef[lv, 3, i, 2] * x2
                 + coef[lv, 4, i, 0] * y0 + coef[lv, 4, i, 1] * y1 + coef[lv, 4, i, 2] * y2
                 - (coef[lv, 2, i, 0] * a[0] + coef[lv, 2, i, 1] * a[1] + coef[lv, 2, i, 2] * a[2]))
    for i in range(3):
        v1[i] = v[i] + h * (coef[lv, 0, i, 0] * a[0] + coef[lv, 0, i, 1] * a[1] + coef[lv, 0, i, 2] * a[2]
                            + coef[lv, 5, i, 0] * a1[0] + coef[lv, 5, i, 1] * a1[1] + coef[lv, 5, i, 2] * a1[2])
    return True, -1, work


@njit(cache=True, error_model="numpy", inline="always")
def step_newmark_implicit(mass, bvec, mult, params, d, v, a, p1, h, es, en, kpeak, d1, v1, a1, r,
                          tol, max_iter):
    """One step of Newmark's average acceleration method (gamma = 1/2, beta = 1/4):

        M a+ + R(d+) = p+,  a+ = 4/h^2 (d+ - d - h v) - a,  v+ = v + h/2 (a + a+)

    solved for d+ by Newton iterations from d + h v + h^2/2 a. The Jacobian is
    4/h^2 M + K_t(d+), K_t = sum mult k_t b b^T with each element's closed-form
    tangent (seed eq. 16) at the trial point on the branch from its start state;
    the 3x3 system is solved by Cramer's rule. Converged when the Newton correction
    is at most tol times the step's increment (both in the norm sqrt(x^T M x)), or
    below the round-off of d+ itself; the accepted iterate is the last one evaluated,
    so en, r and the work belong to d+.
    Returns (ok, bad element or NEWTON_FAILED, element work, iterations).
    """
    c = 4.0 / (h * h)
    for i in range(3):
        d1[i] = d[i] + h * v[i] + 0.5 * h * h * a[i]
    for it in range(max_iter):
        ok, bad, work = update_elements(bvec, mult, params, d1, es, en, kpeak, r)
        if not ok:
            return False, bad, 0.0, it + 1
        k11, k22, k33, k12, k13, k23 = bbt_sums(bvec, mult, en[:, K], mass, False)
        k11 += c * mass[0]
        k22 += c * mass[1]
        k33 += c * mass[2]
        g0 = mass[0] * (c * (d1[0] - d[0] - h * v[0]) - a[0]) + r[0] - p1[0]
        g1 = mass[1] * (c * (d1[1] - d[1] - h * v[1]) - a[1]) + r[1] - p1[1]
        g2 = mass[2] * (c * (d1[2] - d[2] - h * v[2]) - a[2]) + r[2] - p1[2]
        c11 = k22 * k33 - k23 * k23
        c12 = k13 * k23 - k12 * k33
        c13 = k12 * k23 - k13 * k22
        c22 = k11 * k33 - k13 * k13
        c23 = k12 * k13 - k11 * k23
        c33 = k11 * k22 - k12 * k12
        det = k11 * c11 + k12 * c12 + k13 * c13
        x0 = -(c11 * g0 + c12 * g1 + c13 * g2) / det
        x1 = -(c12 * g0 + c22 * g1 + c23 * g2) / det
        x2 = -(c13 * g0 + c23 * g1 + c33 * g2) / det
        corr = mass[0] * x0 * x0 + mass[1] * x1 * x1 + mass[2] * x2 * x2
        incr = (mass[0] * (d1[0] - d[0]) ** 2 + mass[1] * (d1[1] - d[1]) ** 2
                + mass[2] * (d1[2] - d[2]) ** 2)
        # round-off floor: d+ itself is known to a few ulps only (a slow step's increment is tiny)
        floor = ROUNDOFF2 * (mass[0] * d1[0] * d1[0] + mass[1] * d1[1] * d1[1] + mass[2] * d1[2] * d1[2])
        if corr <= tol * tol * incr + floor:
            for i in range(3):
                a1[i] = c * (d1[i] - d[i] - h * v[i]) - a[i]
                v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
            return True, -1, work, it + 1
        if not corr < math.inf:  # NaN or Inf: a singular Jacobian or a runaway iterate
            return False, NEWTON_FAILED, 0.0, it + 1
        d1[0] += x0
        d1[1] += x1
        d1[2] += x2
    return False, NEWTON_FAILED, 0.0, max_iter


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
        out_d, out_v, out_a, out_u, out_f, out_e, info, newton_tol, newton_max_iter):
    """Integrate from the state (d, v, a) at t = 0 over n_steps output steps.

    load: (n_steps * nsub_c + 1, 3) generalized load on the compute grid of step h_c.
    out_*: rows at every ``every``-th output step, row 0 being t = 0.
    out_e columns: input energy, kinetic energy, hysteretic work (cumulative).
    Every compute step is split into at least 2**min_level substeps (a structure-
    dependent method needs omega_0 h within the limit too, see simulate.min_level).
    newton_tol, newton_max_iter: the implicit method's convergence test and iteration cap;
    a step whose iterations fail is retried, like a stiff one, with twice the substeps.
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
    steps_taken = 0
    iterations = 0
    substeps = 0
    level_used = 0
    level = 0
    omega_dt2_seen = 0.0  # (omega h)^2: the square root once, at the end
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
                elif method == KR_ALPHA:
                    ok, bad, work = step_kr_alpha(coef, level, minv, bvec, mult, params, d, v, a, p0, p1, h,
                                                  es, en, kpeak, d1, v1, a1, r)
                elif method == NEWMARK:
                    ok, bad, work, its = step_newmark_implicit(mass, bvec, mult, params, d, v, a, p1, h,
                                                               es, en, kpeak, d1, v1, a1, r,
                                                               newton_tol, newton_max_iter)
                    iterations += its
                else:
                    ok, bad, work = False, -1, 0.0
                steps_taken += 1
                t_now = (j + w1) * h_c
                if not ok:
                    if bad == NEWTON_FAILED and level < max_level:
                        accepted = False  # retry the compute step with twice the substeps
                        break
                    if bad == NEWTON_FAILED:
                        _fail(info, NOT_CONVERGED, -1, t_now, substeps, level_used)
                    else:
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
                if lam * h * h > omega_dt2_seen:
                    omega_dt2_seen = lam * h * h
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
            if method == KR_ALPHA:
                # its acceleration variable is a(t) + O(h): report equilibrium at d instead
                for i in range(3):
                    out_a[row, i] = minv[i] * (load[j + 1, i] - r[i])
            for e in range(ne):
                out_u[row, e] = es[e, U]
                out_f[row, e] = es[e, F]
            out_e[row, 0] = e_in
            out_e[row, 1] = 0.5 * (mass[0] * v[0] ** 2 + mass[1] * v[1] ** 2 + mass[2] * v[2] ** 2)
            out_e[row, 2] = e_hyst

    info[I_STATUS] = OK
    info[I_SUBSTEPS] = substeps
    info[I_LEVEL] = level_used
    info[I_OMEGA_DT] = math.sqrt(omega_dt2_seen)
    info[I_STEPS] = steps_taken
    info[I_ITER] = iterations
    return row
