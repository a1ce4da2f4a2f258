"""The compiled step of every fixed-step method, and the one place where it is chosen.

Every step has the same inputs and outputs, so the loop (rbhyst.solve.kernels.loop) calls
``take_step`` and never grows when a method is added: a new method adds its module (its
coefficients, numpy only), its step here, and one line in ``take_step``. The schemes are
written out in each method's module docstring.
"""

import math

from numba import njit

from rbhyst.solve.kernels.layout import NEWTON_FAILED
from rbhyst.solve.kernels.elements import bbt_sums, mat_row, substep_load, update_elements
from rbhyst.solve.integrators import central_difference, chang, kr_alpha, newmark
from rbhyst.solve.integrators.chang import B1, B2, MC_INV
from rbhyst.solve.integrators.kr_alpha import A_A, A_V, D_A, V_A, V_ANEW, X_NEW, X_OLD
from rbhyst.solve.integrators.newmark import ROUNDOFF2

CHANG = chang.KERNEL_ID
CENTRAL_DIFFERENCE = central_difference.KERNEL_ID
NEWMARK = newmark.KERNEL_ID
KR_ALPHA = kr_alpha.KERNEL_ID


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def chang_step(coef, lv, minv, cm, damped, bvec, mult, params, st, cur,
         d0, d1, d2, v0, v1, v2, a0, a1, a2, load, j, w0, w1, h, kpeak):
    """One step of Chang's method (coef = B1, B2, (M + h/2 C)^-1) or of central difference
    (B1 = I, B2 = I/2), from the element state st[cur] into st[1 - cur].

    Returns (ok, bad element, element work, d+, v+, a+ as nine scalars, R(d+) as three).
    """
    pa0, pa1, pa2, pb0, pb1, pb2 = substep_load(load, j, w0, w1)
    hh = h * h
    n0 = d0 + h * mat_row(coef, lv, B1, 0, v0, v1, v2) + hh * mat_row(coef, lv, B2, 0, a0, a1, a2)
    n1 = d1 + h * mat_row(coef, lv, B1, 1, v0, v1, v2) + hh * mat_row(coef, lv, B2, 1, a0, a1, a2)
    n2 = d2 + h * mat_row(coef, lv, B1, 2, v0, v1, v2) + hh * mat_row(coef, lv, B2, 2, a0, a1, a2)
    ok, bad, work, r0, r1, r2 = update_elements(bvec, mult, params, n0, n1, n2, st, cur, kpeak)
    if not ok:
        return False, bad, 0.0, n0, n1, n2, v0, v1, v2, a0, a1, a2, r0, r1, r2
    x0 = pb0 - r0
    x1 = pb1 - r1
    x2 = pb2 - r2
    if damped:
        w0 = v0 + 0.5 * h * a0
        w1 = v1 + 0.5 * h * a1
        w2 = v2 + 0.5 * h * a2
        x0 -= cm[0, 0] * w0 + cm[0, 1] * w1 + cm[0, 2] * w2
        x1 -= cm[1, 0] * w0 + cm[1, 1] * w1 + cm[1, 2] * w2
        x2 -= cm[2, 0] * w0 + cm[2, 1] * w1 + cm[2, 2] * w2
        b0 = mat_row(coef, lv, MC_INV, 0, x0, x1, x2)
        b1 = mat_row(coef, lv, MC_INV, 1, x0, x1, x2)
        b2 = mat_row(coef, lv, MC_INV, 2, x0, x1, x2)
    else:
        b0 = minv[0] * x0
        b1 = minv[1] * x1
        b2 = minv[2] * x2
    return (True, -1, work, n0, n1, n2,
            v0 + 0.5 * h * (a0 + b0), v1 + 0.5 * h * (a1 + b1), v2 + 0.5 * h * (a2 + b2),
            b0, b1, b2, r0, r1, r2)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def kr_alpha_step(coef, lv, minv, cm, damped, bvec, mult, params, st, cur,
         d0, d1, d2, v0, v1, v2, a0, a1, a2, load, j, w0, w1, h, kpeak):
    """One step of the KR-alpha method (Kolay and Ricles 2014), v being the velocity at t:

        d+ = d + h v + h^2 (A2 - gamma I) a
        a+ = Mh^-1 [(1 - af)(p+ - R+) + af (p - R) - C v] - (coef A_A) a
        v+ = v + h (A1 - gamma I) a + h gamma a+

    (see ``coefficients``). ``a`` is the method's own acceleration variable; R at the
    start of the step comes from the element forces in st[cur].
    Returns (ok, bad element, element work, d+, v+, a+ as nine scalars, R(d+) as three).
    """
    rn0 = 0.0
    rn1 = 0.0
    rn2 = 0.0
    for e in range(bvec.shape[0]):
        mf = mult[e] * st[cur, e, 1]
        rn0 += mf * bvec[e, 0]
        rn1 += mf * bvec[e, 1]
        rn2 += mf * bvec[e, 2]
    pa0, pa1, pa2, pb0, pb1, pb2 = substep_load(load, j, w0, w1)
    hh = h * h
    n0 = d0 + h * v0 + hh * mat_row(coef, lv, D_A, 0, a0, a1, a2)
    n1 = d1 + h * v1 + hh * mat_row(coef, lv, D_A, 1, a0, a1, a2)
    n2 = d2 + h * v2 + hh * mat_row(coef, lv, D_A, 2, a0, a1, a2)
    ok, bad, work, r0, r1, r2 = update_elements(bvec, mult, params, n0, n1, n2, st, cur, kpeak)
    if not ok:
        return False, bad, 0.0, n0, n1, n2, v0, v1, v2, a0, a1, a2, r0, r1, r2
    x0 = pb0 - r0
    x1 = pb1 - r1
    x2 = pb2 - r2
    y0 = pa0 - rn0
    y1 = pa1 - rn1
    y2 = pa2 - rn2
    b0 = mat_row(coef, lv, X_NEW, 0, x0, x1, x2) + mat_row(coef, lv, X_OLD, 0, y0, y1, y2) \
        - mat_row(coef, lv, A_A, 0, a0, a1, a2)
    b1 = mat_row(coef, lv, X_NEW, 1, x0, x1, x2) + mat_row(coef, lv, X_OLD, 1, y0, y1, y2) \
        - mat_row(coef, lv, A_A, 1, a0, a1, a2)
    b2 = mat_row(coef, lv, X_NEW, 2, x0, x1, x2) + mat_row(coef, lv, X_OLD, 2, y0, y1, y2) \
        - mat_row(coef, lv, A_A, 2, a0, a1, a2)
    if damped:
        b0 -= mat_row(coef, lv, A_V, 0, v0, v1, v2)
        b1 -= mat_row(coef, lv, A_V, 1, v0, v1, v2)
        b2 -= mat_row(coef, lv, A_V, 2, v0, v1, v2)
    w0 = v0 + h * (mat_row(coef, lv, V_A, 0, a0, a1, a2) + mat_row(coef, lv, V_ANEW, 0, b0, b1, b2))
    w1 = v1 + h * (mat_row(coef, lv, V_A, 1, a0, a1, a2) + mat_row(coef, lv, V_ANEW, 1, b0, b1, b2))
    w2 = v2 + h * (mat_row(coef, lv, V_A, 2, a0, a1, a2) + mat_row(coef, lv, V_ANEW, 2, b0, b1, b2))
    return True, -1, work, n0, n1, n2, w0, w1, w2, b0, b1, b2, r0, r1, r2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def newmark_step(mass, cm, damped, bvec, mult, params, st, cur,
         d0, d1, d2, v0, v1, v2, a0, a1, a2, load, j, w0, w1, h, kpeak, tol, max_iter):
    """One Newmark step solved for d+ by Newton iterations from d + h v + h^2/2 a.

    The Jacobian is 4/h^2 M + 2/h C + K_t(d+), K_t = sum mult k_t b b^T with each
    element's closed-form tangent (seed eq. 16) at the trial point on the branch from its
    start state; the 3x3 system is solved by Cramer's rule. Converged when the Newton
    correction is at most tol times the step's increment (both in the norm sqrt(x^T M x)),
    or below the round-off of d+ itself; the accepted iterate is the last one evaluated,
    so st[1 - cur], R and the work belong to d+.
    Returns (ok, bad element or NEWTON_FAILED, element work, iterations, d+, v+, a+, R(d+)).
    """
    _, _, _, p0, p1, p2 = substep_load(load, j, w0, w1)
    c = 4.0 / (h * h)
    cv = 2.0 / h
    n0 = d0 + h * v0 + 0.5 * h * h * a0
    n1 = d1 + h * v1 + 0.5 * h * h * a1
    n2 = d2 + h * v2 + 0.5 * h * h * a2
    for it in range(max_iter):
        ok, bad, work, r0, r1, r2 = update_elements(bvec, mult, params, n0, n1, n2, st, cur, kpeak)
        if not ok:
            return False, bad, 0.0, it + 1, n0, n1, n2, v0, v1, v2, a0, a1, a2, r0, r1, r2
        k11, k22, k33, k12, k13, k23 = bbt_sums(bvec, mult, kpeak, 1, mass, False)
        k11 += c * mass[0]
        k22 += c * mass[1]
        k33 += c * mass[2]
        g0 = mass[0] * (c * (n0 - d0 - h * v0) - a0) + r0 - p0
        g1 = mass[1] * (c * (n1 - d1 - h * v1) - a1) + r1 - p1
        g2 = mass[2] * (c * (n2 - d2 - h * v2) - a2) + r2 - p2
        if damped:
            w0 = cv * (n0 - d0) - v0
            w1 = cv * (n1 - d1) - v1
            w2 = cv * (n2 - d2) - v2
            g0 += cm[0, 0] * w0 + cm[0, 1] * w1 + cm[0, 2] * w2
            g1 += cm[1, 0] * w0 + cm[1, 1] * w1 + cm[1, 2] * w2
            g2 += cm[2, 0] * w0 + cm[2, 1] * w1 + cm[2, 2] * w2
            k11 += cv * cm[0, 0]
            k22 += cv * cm[1, 1]
            k33 += cv * cm[2, 2]
            k12 += cv * cm[0, 1]
            k13 += cv * cm[0, 2]
            k23 += cv * cm[1, 2]
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
        incr = mass[0] * (n0 - d0) ** 2 + mass[1] * (n1 - d1) ** 2 + mass[2] * (n2 - d2) ** 2
        # round-off floor: d+ itself is known to a few ulps only (a slow step's increment is tiny)
        floor = ROUNDOFF2 * (mass[0] * n0 * n0 + mass[1] * n1 * n1 + mass[2] * n2 * n2)
        if corr <= tol * tol * incr + floor:
            b0 = c * (n0 - d0 - h * v0) - a0
            b1 = c * (n1 - d1 - h * v1) - a1
            b2 = c * (n2 - d2 - h * v2) - a2
            return (True, -1, work, it + 1, n0, n1, n2,
                    v0 + 0.5 * h * (a0 + b0), v1 + 0.5 * h * (a1 + b1), v2 + 0.5 * h * (a2 + b2),
                    b0, b1, b2, r0, r1, r2)
        if not corr < math.inf:  # NaN or Inf: a singular Jacobian or a runaway iterate
            return False, NEWTON_FAILED, 0.0, it + 1, n0, n1, n2, v0, v1, v2, a0, a1, a2, r0, r1, r2
        n0 += x0
        n1 += x1
        n2 += x2
    return False, NEWTON_FAILED, 0.0, max_iter, n0, n1, n2, v0, v1, v2, a0, a1, a2, 0.0, 0.0, 0.0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def take_step(method, coef, lv, mass, minv, cm, damped, bvec, mult, params, st, cur,
              d0, d1, d2, v0, v1, v2, a0, a1, a2, load, j, w0, w1, h, kpeak, tol, max_iter):
    """Advance one (sub)step of size h from the state (d, v, a); the load is linear within
    compute step j of ``load``, the substep spanning the fractions w0 to w1 of it (at most 30
    arguments: more would make Python pass them as a tuple, which numba cannot inline).

    Returns (ok, bad element, element work, iterations, d+, v+, a+, R(d+)) as scalars.
    """
    if method == NEWMARK:
        return newmark_step(mass, cm, damped, bvec, mult, params, st, cur, d0, d1, d2, v0, v1, v2,
                            a0, a1, a2, load, j, w0, w1, h, kpeak, tol, max_iter)
    if method == KR_ALPHA:
        ok, bad, w, n0, n1, n2, w0, w1, w2, b0, b1, b2, r0, r1, r2 = kr_alpha_step(
            coef, lv, minv, cm, damped, bvec, mult, params, st, cur, d0, d1, d2, v0, v1, v2, a0, a1, a2,
            load, j, w0, w1, h, kpeak)
        return ok, bad, w, 1, n0, n1, n2, w0, w1, w2, b0, b1, b2, r0, r1, r2
    # Chang's method and central difference share their step (their coefficients differ)
    ok, bad, w, n0, n1, n2, w0, w1, w2, b0, b1, b2, r0, r1, r2 = chang_step(
        coef, lv, minv, cm, damped, bvec, mult, params, st, cur, d0, d1, d2, v0, v1, v2, a0, a1, a2,
        load, j, w0, w1, h, kpeak)
    return ok, bad, w, 1, n0, n1, n2, w0, w1, w2, b0, b1, b2, r0, r1, r2
