"""KR-alpha: Kolay and Ricles' explicit, structure-dependent alpha family (2014).

With rho_inf in [0, 1] the spectral radius at infinite frequency,

    am = (2 rho_inf - 1) / (rho_inf + 1),  af = rho_inf / (rho_inf + 1),
    gamma = 1/2 - am + af,  beta = (1 - am + af)^2 / 4,
    A = M + beta dt^2 K0,  A1 = A^-1 M,  A2 = (1/2 + gamma) A1,
    A3 = A^-1 (am M + af beta dt^2 K0),

the published step (same coefficients as OpenSees' KRAlphaExplicit) is

    v+ = v + dt A1 a,  d+ = d + dt v + dt^2 A2 a,
    M (I - A3) a+ = p(t+ - af) - R(+ - af) - M A3 a,  x(+ - af) = (1 - af) x+ + af x,

with the restoring force interpolated between the ends of the step (the element
state is only ever evaluated at d+).

Its velocity variable is v(t) - gamma dt a(t) + O(dt^2) (a modified-equation
argument, checked numerically): started from v(0) with a(0) != 0 it costs the
displacement an order, and read as v(t) it is first-order accurate. This module
therefore runs the same recursion on the velocity at t itself:

    d+ = d + dt v + dt^2 (A2 - gamma I) a,  v+ = v + dt (A1 - gamma I) a + dt gamma a+,

which keeps displacements and velocities second order from any initial state and
across changes of the substep. The acceleration variable ``a`` is the method's own
(a(t) + O(dt)); the loop reports equilibrium M^-1 (p - R(d)) instead.

Order 2. Unconditionally stable while the tangent stiffness stays at or below K0
(like Chang's method; conditionally stable on stiffening branches, which the loop's
monitor catches). Numerical dissipation grows with omega dt towards rho_inf at
infinite frequency: rho_inf = 1 is non-dissipative (on linear systems it then
coincides with Chen and Ricles' CR method), rho_inf = 0 annihilates the highest
modes in one step. The registered ``kr-alpha`` uses rho_inf = 0.5; ``method(rho)``
builds another member of the family.
"""

from __future__ import annotations

import functools

import numpy as np

from rbhyst.solve.integrators import N_COEF, Method

RHO_INF = 0.5
KERNEL_ID = 3
# coefficient slots
V_A, D_A, A_A, X_NEW, X_OLD, V_ANEW, A_V = range(7)


def parameters(rho_inf: float) -> tuple[float, float, float, float]:
    """(am, af, gamma, beta) of the family member with spectral radius rho_inf at infinity."""
    if not 0.0 <= rho_inf <= 1.0:
        raise ValueError(f"rho_inf = {rho_inf} must be in [0, 1]")
    am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    af = rho_inf / (rho_inf + 1.0)
    gamma = 0.5 - am + af
    beta = 0.25 * (1.0 - am + af) ** 2
    return am, af, gamma, beta


def coefficients(mass: np.ndarray, k0: np.ndarray, c: np.ndarray, h: float, rho_inf: float = RHO_INF) -> np.ndarray:
    """The step's matrices; with the velocity at t (module docstring) and viscous damping C:

        Mh a+ = (1 - af)(p+ - R+) + af (p - R) - (M A3 + (1 - af) h C (A1 - gamma I)) a - C v,
        Mh = M (I - A3) + (1 - af) gamma h C,

    A3 from A = M + gamma h C + beta h^2 K0 as published, A1 = (M + beta h^2 K0)^-1 M.
    """
    am, af, gamma, beta = parameters(rho_inf)
    h = np.asarray(h, dtype=float)[..., None, None]  # (an array of steps: a set for each)
    m = np.diag(mass)
    eye = np.eye(len(mass))
    big_a = m + gamma * h * c + beta * h * h * k0
    # the velocity and displacement updates' A1 without C: with it, A1 - I = -gamma h M^-1 C +
    # O(h^2) puts an O(h^2) error into every step's velocity on the velocity at t, and a damped
    # run was first order (0.55 % at 1 ms where chang has 0.008 %); without it A1 - I = O(h^2)
    # and the spectral radius over omega h and damping ratios 0-5 is unchanged
    a1 = np.linalg.solve(m + beta * h * h * k0, np.broadcast_to(m, big_a.shape))
    a2 = (0.5 + gamma) * a1
    a3 = np.linalg.solve(big_a, am * m + af * gamma * h * c + af * beta * h * h * k0)
    mh_inv = np.linalg.inv(m @ (eye - a3) + (1.0 - af) * gamma * h * c)
    out = np.zeros(h.shape[:-2] + (N_COEF, len(mass), len(mass)))
    out[..., V_A, :, :] = a1 - gamma * eye
    out[..., D_A, :, :] = a2 - gamma * eye
    out[..., A_A, :, :] = mh_inv @ (m @ a3 + (1.0 - af) * h * c @ (a1 - gamma * eye))
    out[..., X_NEW, :, :] = (1.0 - af) * mh_inv
    out[..., X_OLD, :, :] = af * mh_inv
    out[..., V_ANEW, :, :] = gamma * eye
    out[..., A_V, :, :] = mh_inv @ c
    return out


def method(rho_inf: float = RHO_INF, name: str | None = None) -> Method:
    parameters(rho_inf)  # validate
    return Method(
        name=name or f"kr-alpha-{rho_inf:g}",
        summary=f"KR-alpha (rho_inf = {rho_inf:g}): explicit, unconditionally stable up to K0, "
                "tunable high-frequency dissipation",
        order=2,
        explicit=True,
        kernel_id=KERNEL_ID,
        structure_dependent=True,
        coefficients=functools.partial(coefficients, rho_inf=rho_inf),
    )


METHOD = method(RHO_INF, name="kr-alpha")
