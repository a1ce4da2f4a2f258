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

This module is plain numpy (decks, plots, tests, calibration import it without
compiling anything); the compiled scalar kernels the time stepping calls are in
:mod:`rbhyst.model.vrm`, with :func:`~rbhyst.model.vrm.loop`, the force history of an
imposed displacement.
"""

from __future__ import annotations

import math

import numpy as np

PARAMS = ("kb", "f0", "alpha", "beta1", "beta2", "gamma1", "gamma2", "gamma3")
KB, F0, ALPHA, BETA1, BETA2, GAMMA1, GAMMA2, GAMMA3 = range(8)
#: a stop's parameters (rbhyst.model.stop): the third row of an element's kernel parameters after its
#: VRM branches (rbhyst.model.system.System.kernel_params), here where importing loads no numba
STOP_ROW = 2
STOP_LOWER, STOP_UPPER, STOP_K, STOP_E = 0, 1, 2, 3  # gaps (m, lower < 0 < upper; +-inf: none), N/m, ratio
LOADING, UNLOADING = 0, 1

#: Largest beta2*u for which exp() is finite with room to spare: beyond it an
#: element has left any range it could have been calibrated on.
EXP_ARG_MAX = 700.0
LN2 = math.log(2.0)


def parameter_set(loading: dict, unloading: dict) -> np.ndarray:
    """Build the ``(2, 8)`` parameter array from two dicts of branch parameters."""
    arr = np.zeros((2, 8))
    for row, branch in ((LOADING, loading), (UNLOADING, unloading)):
        for k, name in enumerate(PARAMS):
            arr[row, k] = float(branch.get(name, 0.0))
    return arr


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


def limiting_slope(p: np.ndarray, s: int, u) -> np.ndarray:
    """dc_s/du = kb_s + ke_s(u), eq. 17."""
    row = LOADING if s > 0 else UNLOADING
    kb, f0, _, b1, b2, g1, g2, g3 = p[row]
    u = np.asarray(u, dtype=float)
    k = kb + 0.0 * u
    if b1 != 0.0 and b2 != 0.0:
        k = k + b1 * b2 * np.exp(b2 * u)
    if g1 != 0.0 and g2 != 0.0:
        k = k + g1 * g2 / np.cosh(0.5 * g2 * (u - g3)) ** 2
    return k


def reversal_stiffness(p: np.ndarray, u=0.0) -> float:
    """Largest tangent at a reversal at displacement u: kb_s + ke_s + alpha_s * gap.

    The gap c_+(u) - c_-(u) is the most a branch can be away from the curve it
    tends to; in the symmetric case at u = 0 this is k_a = kb + alpha (f0+ + f0-).
    """
    gap = float(limiting_curve(p, 1, u) - limiting_curve(p, -1, u))
    ks = []
    for s, row in ((1.0, LOADING), (-1.0, UNLOADING)):
        kc = limiting_slope(p, s, u)
        ks.append(kc + p[row, ALPHA] * gap)
    return max(ks)


def virgin_tangent(p: np.ndarray, s: float) -> float:
    """Tangent at the virgin state (u, f) = (0, 0) moving in direction s (eq. 16)."""
    row = LOADING if s > 0 else UNLOADING
    c = float(limiting_curve(p, s, 0.0))
    return float(limiting_slope(p, s, 0.0)) + s * p[row, ALPHA] * c
