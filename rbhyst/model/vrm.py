"""Compiled scalar kernels of the Vaiana-Rosati model (seed eqs. 14-17), called from the time
stepping loops; the parameter layout and the numpy functions are in :mod:`rbhyst.model.hysteresis`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rbhyst.model.hysteresis import (ALPHA, BETA1, BETA2, EXP_ARG_MAX, F0, GAMMA1, GAMMA2, GAMMA3, KB, LN2, LOADING, UNLOADING)


@njit(cache=True, error_model="numpy", inline="always")
def branch_row(s):
    return LOADING if s > 0 else UNLOADING


@njit(cache=True, error_model="numpy", inline="always")
def branch_eval(p, e, row, s, u):
    """The limiting curve c_s at u (eqs. 14-15), its slope kb + ke (eq. 17) and its
    antiderivative C_s(u) (for the work, seed ref. [8]); ``ok`` is False on overflow.

    Terms with a zero amplitude are skipped, so a set without beta and gamma terms
    costs no transcendental function here at all.
    """
    kb = p[e, row, KB]
    f0 = p[e, row, F0]
    c = kb * u + s * f0
    kc = kb
    big = u * (0.5 * kb * u + s * f0)
    b1 = p[e, row, BETA1]
    b2 = p[e, row, BETA2]
    if b1 != 0.0 and b2 != 0.0:
        x = b2 * u
        if x > EXP_ARG_MAX:
            return c, kc, big, False
        # expm1 keeps c and C_s exact as beta2 -> 0 (C_s = b1 (expm1(b2 u)/b2 - u) -> 0)
        em = math.expm1(x)
        c += b1 * em
        kc += b1 * b2 * (em + 1.0)
        if abs(x) < 1e-5:  # em / b2 - u by its series: exact even where b2 u underflows
            big += b1 * u * x * (0.5 + x / 6.0)
        else:
            big += b1 * (em / b2 - u)
    g1 = p[e, row, GAMMA1]
    g2 = p[e, row, GAMMA2]
    if g1 != 0.0 and g2 != 0.0:
        x = 0.5 * g2 * (u - p[e, row, GAMMA3])
        t = math.tanh(x)
        c += 2.0 * g1 * t
        kc += g1 * g2 * (1.0 - t * t)
        # d/du (4 g1 / g2) log cosh(x) = 2 g1 tanh(x); log cosh without cancellation
        # for small x (gamma2 -> 0 multiplies it by 4 g1 / g2) and without overflow for large
        ax = abs(x)
        if ax < 0.5:
            sh = math.sinh(0.5 * ax)
            lc = math.log1p(2.0 * sh * sh)
        else:
            lc = ax + math.log1p(math.exp(-2.0 * ax)) - LN2
        big += 4.0 * g1 / g2 * lc
    return c, kc, big, True


@njit(cache=True, error_model="numpy", inline="always")
def vrm_update(p, e, u0, f0, s0, g0, k0, a0, u1):
    """Advance element e of the (ne, 2, 8) parameter stack p from (u0, f0) on
    branch s0 to displacement u1 (eq. 14).

    The element state is (u, f, s, g, k, a): displacement, force, branch sign
    (0 for the virgin state), gap g = c_s(u) - f, tangent k (eq. 16) and the
    antiderivative a = C_s(u) of the current limiting curve.
    Returns ``(f1, s1, g1, k1, a1, kstart, work, ok)``: the new state, the tangent
    at the start of the step on the (possibly new) branch, the work of the force
    over the step (exact, closed form) and False where an exponential overflowed.
    """
    du = u1 - u0
    if du == 0.0:
        return f0, s0, g0, k0, a0, k0, 0.0, True
    s = 1.0 if du > 0.0 else -1.0
    row = branch_row(s)
    alpha = p[e, row, ALPHA]
    if s != s0:
        # a reversal (or the first move from the virgin state): a new branch
        # starts at (u0, f0), eq. 14 with t_P = now
        c_a, kc_a, a_start, ok = branch_eval(p, e, row, s, u0)
        if not ok:
            return f0, s0, g0, k0, a0, k0, 0.0, False
        g = c_a - f0
        kstart = kc_a + s * alpha * g
    else:
        g = g0
        kstart = k0
        a_start = a0
    decay = math.exp(-alpha * abs(du))
    c_b, kc_b, a1, ok = branch_eval(p, e, row, s, u1)
    if not ok:
        return f0, s0, g0, k0, a0, kstart, 0.0, False
    g1 = g * decay
    f1 = c_b - g1
    k1 = kc_b + s * alpha * g1
    # integral of f = c_s - g exp(-alpha |u - u0|) over the step
    work = a1 - a_start + s * g * (decay - 1.0) / alpha
    return f1, s, g1, k1, a1, kstart, work, True


@njit(cache=True, error_model="numpy")
def drive(p, u, f_out, k_out, w_out):
    """Impose the displacement history ``u`` on one element (p: (2, 8)) from the virgin state.

    Writes force, tangent and cumulative work at every sample; returns the index of
    the first sample where an exponential overflowed, or -1.
    """
    stack = p.reshape((1, 2, 8))
    f = 0.0
    s = 0.0
    g = 0.0
    k = 0.0
    a = 0.0
    w = 0.0
    uprev = 0.0
    for i in range(u.shape[0]):
        f, s, g, k, a, _, dw, ok = vrm_update(stack, 0, uprev, f, s, g, k, a, u[i])
        if not ok:
            return i
        w += dw
        uprev = u[i]
        f_out[i] = f
        k_out[i] = k
        w_out[i] = w
    return -1


def loop(p: np.ndarray, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Force, tangent and cumulative work for an imposed history ``u`` from the virgin state.

    A reversal is placed at every sample where the displacement increment changes sign.
    """
    u = np.ascontiguousarray(u, dtype=float)
    f = np.empty_like(u)
    k = np.empty_like(u)
    w = np.empty_like(u)
    bad = drive(np.ascontiguousarray(p, dtype=float), u, f, k, w)
    if bad >= 0:
        raise OverflowError(
            f"exp overflow at sample {bad} (u = {u[bad]:.6g}): the displacement is far "
            "outside any range the set could have been calibrated on"
        )
    return f, k, w
