"""Element rows at a new configuration (seed eqs. 5-17) and the stiffness bounds of the monitor.

Compiled with numba; called from the time-stepping loop and from each method's step.
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.model.vrm import vrm_update
from rbhyst.solve.kernels.layout import A, F, G, K, S, U


@njit(cache=True, error_model="numpy", _nrt=False)
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


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def update_elements(bvec, mult, params, q0, q1, q2, st, cur, kpeak):
    """Elements at the new configuration q (eqs. 5-11).

    st: (2, ne, 6) element states; st[cur] holds the state at the start of the step
    (columns U, F, S, G, K, A, see hysteresis.vrm_update), st[1 - cur] receives the new
    state (two buffers used in turn: an accepted step copies nothing); kpeak (ne, 2) receives
    the largest tangent over the step and the tangent at its end.
    Returns (ok, bad element, work of all element forces over the step, and the
    restoring force sum mult b f as three scalars).
    """
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    work = 0.0
    for e in range(bvec.shape[0]):
        b0 = bvec[e, 0]
        b1 = bvec[e, 1]
        b2 = bvec[e, 2]
        u = b0 * q0 + b1 * q1 + b2 * q2
        f, s, g, k, a, kstart, w, ok = vrm_update(params, e, st[cur, e, U], st[cur, e, F], st[cur, e, S],
                                                  st[cur, e, G], st[cur, e, K], st[cur, e, A], u)
        if not ok:
            return False, e, work, r0, r1, r2
        nxt = 1 - cur
        st[nxt, e, U] = u
        st[nxt, e, F] = f
        st[nxt, e, S] = s
        st[nxt, e, G] = g
        st[nxt, e, K] = k
        st[nxt, e, A] = a
        kpeak[e, 0] = max(kstart, k)
        kpeak[e, 1] = k
        m = mult[e]
        work += m * w
        mf = m * f
        r0 += mf * b0
        r1 += mf * b1
        r2 += mf * b2
    return True, -1, work, r0, r1, r2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def omega_squared(mult, kpeak, wgt):
    """Trace bound on omega_max^2 = max eig(M^-1 K), K = sum mult k b b^T (k = kpeak[:, 0] >= 0).

    wgt[e] = b_e^T M^-1 b_e. Returns the bound and the element with the largest share of
    it; the exact eigenvalue (omega_squared_exact) is computed only when the bound is too high.
    """
    trace = 0.0
    worst = 0
    share = -1.0
    for e in range(mult.shape[0]):
        c = mult[e] * max(kpeak[e, 0], 0.0) * wgt[e]
        trace += c
        if c > share:
            share = c
            worst = e
    return trace, worst


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def bbt_sums(bvec, mult, k, col, minv, normalized):
    """The six entries (11, 22, 33, 12, 13, 23) of K = sum mult k_e b_e b_e^T with k_e = k[e, col]
    (k: (ne, m)),
    or where ``normalized`` of M^-1/2 K M^-1/2 with negative k_e taken as 0 (for omega_max^2)."""
    s11 = s22 = s33 = s12 = s13 = s23 = 0.0
    q0 = math.sqrt(minv[0]) if normalized else 1.0
    q1 = math.sqrt(minv[1]) if normalized else 1.0
    q2 = math.sqrt(minv[2]) if normalized else 1.0
    for e in range(bvec.shape[0]):
        ke = mult[e] * (max(k[e, col], 0.0) if normalized else k[e, col])
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


@njit(cache=True, error_model="numpy", _nrt=False)
def omega_squared_exact(bvec, mult, minv, kpeak):
    """max eig(M^-1/2 K M^-1/2), the exact omega_max^2 of the tangent system (kpeak: (ne, 2), column 0)."""
    s11, s22, s33, s12, s13, s23 = bbt_sums(bvec, mult, kpeak, 0, minv, True)
    return sym3_max_eig(s11, s22, s33, s12, s13, s23)


@njit(cache=True, error_model="numpy", _nrt=False)
def copy_rows(src, dst):
    """dst[:] = src for (n, m) arrays, without a temporary."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def mat_row(c, lv, k, i, x0, x1, x2):
    """Row i of the coefficient matrix c[lv, k] times (x0, x1, x2)."""
    return c[lv, k, i, 0] * x0 + c[lv, k, i, 1] * x1 + c[lv, k, i, 2] * x2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def substep_load(load, j, w0, w1):
    """The load at the fractions w0 and w1 of compute step j, linear within it (six scalars)."""
    pa0 = load[j, 0] + w0 * (load[j + 1, 0] - load[j, 0])
    pa1 = load[j, 1] + w0 * (load[j + 1, 1] - load[j, 1])
    pa2 = load[j, 2] + w0 * (load[j + 1, 2] - load[j, 2])
    pb0 = load[j, 0] + w1 * (load[j + 1, 0] - load[j, 0])
    pb1 = load[j, 1] + w1 * (load[j + 1, 1] - load[j, 1])
    pb2 = load[j, 2] + w1 * (load[j + 1, 2] - load[j, 2])
    return pa0, pa1, pa2, pb0, pb1, pb2
