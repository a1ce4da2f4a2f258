"""Vaiana-Rosati model (VRM) of rate-independent hysteresis, seed eqs. 14-17.

A parameter set is a ``(2, 8)`` float array: row 0 holds the loading branch
(``s > 0``), row 1 the unloading branch (``s < 0``); the columns are
``kb, f0, alpha, beta1, beta2, gamma1, gamma2, gamma3`` (see ``PARAMS``).

With ``c_s(u) = fe_s(u) + kb_s u + s f0_s`` the upper (s = +1) or lower
(s = -1) limiting curve, eq. 14 reads

    f(u) = c_s(u) - g_P exp(-s alpha_s (u - u_P)),   g_P = c_s(u_P) - f(u_P).

``g = c_s(u) - f(u)`` is the gap between the force and the limiting curve the
branch tends to; along a branch it decays as ``g(u) = g_P exp(-alpha |u - u_P|)``.
Restarting a branch from any point on it gives the same branch, so a time
stepper carries ``(u, f, s, g)`` per element and needs no other memory.

The logistic term of eq. 15 is written ``2 gamma1 tanh(gamma2 (u - gamma3) / 2)``,
which is the same function and cannot overflow.

The scalar kernels are compiled with numba and are called from the time
stepping loop; the array functions below are plain numpy for plots, tests and
calibration.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

PARAMS = ("kb", "f0", "alpha", "beta1", "beta2", "gamma1", "gamma2", "gamma3")
KB, F0, ALPHA, BETA1, BETA2, GAMMA1, GAMMA2, GAMMA3 = range(8)
LOADING, UNLOADING = 0, 1

#: Largest beta2*u for which exp() is finite with room to spare: beyond it an
#: element has left any range it could have been calibrated on.
EXP_ARG_MAX = 700.0


def parameter_set(loading: dict, unloading: dict) -> np.ndarray:
    """Build the ``(2, 8)`` parameter array from two dicts of branch parameters."""
    arr = np.zeros((2, 8))
    for row, branch in ((LOADING, loading), (UNLOADING, unloading)):
        for k, name in enumerate(PARAMS):
            arr[row, k] = float(branch.get(name, 0.0))
    return arr


# --------------------------------------------------------------------------
# compiled scalar kernels (used by the time-stepping loop)
# --------------------------------------------------------------------------


@njit(cache=True, inline="always")
def branch_row(s):
    return LOADING if s > 0 else UNLOADING


@njit(cache=True)
def fe_ke(p, row, u):
    """Eq. 15 and eq. 17 on one branch: (fe, ke, ok). ``ok`` is False on overflow.

    Terms with a zero amplitude are skipped, so a bilinear-like set costs no exp.
    """
    fe = 0.0
    ke = 0.0
    b1 = p[row, BETA1]
    b2 = p[row, BETA2]
    if b1 != 0.0 and b2 != 0.0:
        x = b2 * u
        if x > EXP_ARG_MAX:
            return fe, ke, False
        e = math.exp(x)
        fe += b1 * (e - 1.0)
        ke += b1 * b2 * e
    g1 = p[row, GAMMA1]
    g2 = p[row, GAMMA2]
    if g1 != 0.0 and g2 != 0.0:
        t = math.tanh(0.5 * g2 * (u - p[row, GAMMA3]))
        fe += 2.0 * g1 * t
        ke += g1 * g2 * (1.0 - t * t)
    return fe, ke, True


@njit(cache=True)
def limiting_integral(p, row, s, ua, ub):
    """Integral of the limiting curve c_s from ua to ub (closed form)."""
    du = ub - ua
    w = (0.5 * p[row, KB] * (ua + ub) + s * p[row, F0]) * du
    b1 = p[row, BETA1]
    b2 = p[row, BETA2]
    if b1 != 0.0 and b2 != 0.0:
        w += b1 * (math.exp(b2 * ua) * math.expm1(b2 * du) / b2 - du)
    g1 = p[row, GAMMA1]
    g2 = p[row, GAMMA2]
    if g1 != 0.0 and g2 != 0.0:
        # d/du [ (4 g1/g2) log cosh(g2 (u - g3)/2) ] = 2 g1 tanh(g2 (u - g3)/2)
        xa = 0.5 * g2 * (ua - p[row, GAMMA3])
        xb = 0.5 * g2 * (ub - p[row, GAMMA3])
        w += 4.0 * g1 / g2 * (_log_cosh(xb) - _log_cosh(xa))
    return w


@njit(cache=True, inline="always")
def _log_cosh(x):
    ax = abs(x)
    return ax + math.log1p(math.exp(-2.0 * ax)) - math.log(2.0)


@njit(cache=True)
def vrm_update(p, u0, f0, s0, g0, k0, u1):
    """Advance one element from (u0, f0) on branch s0 to displacement u1 (eq. 14).

    ``g0`` is the gap c_s0(u0) - f0 and ``k0`` the tangent at u0 (eq. 16).
    Returns ``(f1, s1, g1, k1, kstart, work, ok)``: the new force, branch, gap,
    tangent, the tangent at the start of the step on the (possibly new) branch,
    the work of the force over the step (closed form) and an overflow flag.
    """
    du = u1 - u0
    if du == 0.0:
        return f0, s0, g0, k0, k0, 0.0, True
    s = 1.0 if du > 0.0 else -1.0
    row = branch_row(s)
    alpha = p[row, ALPHA]
    kb = p[row, KB]
    if s != s0:
        # a reversal (or the first move from the virgin state): a new branch
        # starts at (u0, f0), eq. 14 with t_P = the current time
        fe_a, ke_a, ok = fe_ke(p, row, u0)
        if not ok:
            return f0, s0, g0, k0, k0, 0.0, False
        g = fe_a + kb * u0 + s * p[row, F0] - f0
        kstart = ke_a + kb + s * alpha * g
    else:
        g = g0
        kstart = k0
    decay = math.exp(-alpha * abs(du))
    fe_b, ke_b, ok = fe_ke(p, row, u1)
    if not ok:
        return f0, s0, g0, k0, kstart, 0.0, False
    g1 = g * decay
    f1 = fe_b + kb * u1 + s * p[row, F0] - g1
    k1 = ke_b + kb + s * alpha * g1
    # work: integral of c_s minus integral of the decaying gap
    work = limiting_integral(p, row, s, u0, u1) + g * math.expm1(-alpha * abs(du)) / alpha * s
    return f1, s, g1, k1, kstart, work, True


@njit(cache=True)
def drive(p, u, f_out, k_out, w_out):
    """Impose the displacement history ``u`` on one element from the virgin state.

    Writes force, tangent and cumulative work at every sample; returns the index of
    the first sample where an exponential overflowed, or -1.
    """
    f = 0.0
    s = 0.0
    g = 0.0
    k = virgin_tangent(p, 1.0) if u.shape[0] > 1 and u[1] >= u[0] else virgin_tangent(p, -1.0)
    w = 0.0
    uprev = 0.0
    for i in range(u.shape[0]):
        f, s, g, k, _, dw, ok = vrm_update(p, uprev, f, s, g, k, u[i])
        if not ok:
            return i
        w += dw
        uprev = u[i]
        f_out[i] = f
        k_out[i] = k
        w_out[i] = w
    return -1


@njit(cache=True)
def virgin_tangent(p, s):
    """Tangent at the virgin state (u, f) = (0, 0) moving in direction s (eq. 16)."""
    row = branch_row(s)
    fe, ke, _ = fe_ke(p, row, 0.0)
    c = fe + s * p[row, F0]
    return ke + p[row, KB] + s * p[row, ALPHA] * c


# --------------------------------------------------------------------------
# numpy functions on arrays (plots, checks, calibration)
# --------------------------------------------------------------------------


def limiting_curve(p: np.ndarray, s: int, u) -> np.ndarray:
    """c_s(u) = fe_s(u) + kb_s u + s f0_s: the curve a branch of sign s tends to."""
    row = LOADING if s > 0 else UNLOADING
    kb, f0, _, b1, b2, g1, g2, g3 = p[row]
    u = np.asarray(u, dtype=float)
    c = kb * u + s * f0
    if b1 != 0.0 and b2 != 0.0:
        c = c + b1 * np.expm1(b2 * u)
    if g1 != 0.0 and g2 != 0.0:
        c = c + 2.0 * g1 * np.tanh(0.5 * g2 * (u - g3))
    return c


def reversal_stiffness(p: np.ndarray, u=0.0) -> float:
    """Largest tangent at a reversal at displacement u: kb_s + ke_s + alpha_s * gap.

    The gap c_+(u) - c_-(u) is the most a branch can be away from the curve it
    tends to; in the symmetric case at u = 0 this is k_a = kb + alpha (f0+ + f0-).
    """
    gap = float(limiting_curve(p, 1, u) - limiting_curve(p, -1, u))
    ks = []
    for s in (1.0, -1.0):
        row = branch_row(s)
        _, ke, _ = fe_ke(p, row, float(u))
        ks.append(ke + p[row, KB] + p[row, ALPHA] * gap)
    return max(ks)


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
