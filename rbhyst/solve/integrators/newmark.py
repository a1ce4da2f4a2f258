"""Newmark's average acceleration method (gamma = 1/2, beta = 1/4), implicit.

    M a+ + C v+ + R(d+) = p+,  d+ = d + dt v + dt^2/4 (a + a+),  v+ = v + dt/2 (a + a+)

Each step solves for d+ by Newton iterations on the residual
M a+(d+) + C v+(d+) + R(d+) - p+ with the Jacobian 4/dt^2 M + 2/dt C + K_t, K_t
assembled from every element's closed-form tangent (seed eq. 16) at the trial point.
Converged when the correction is at most ``Settings.newton_tol`` (default 1e-10) times
the step's increment in the mass norm sqrt(x^T M x); after ``Settings.newton_max_iter``
(default 20) iterations the compute step is retried with twice the substeps, and a
run that still fails at the finest level stops with a clear message.

Order 2. Unconditionally stable for linear systems and for any softening tangent,
energy conserving on linear systems (no numerical dissipation, period elongation
of order (omega dt)^2 / 12). Its stability does not rest on K0, so there is no
omega_0 dt limit; the loop's stiffness monitor (omega_max dt <= max_omega_dt) still
applies, as an accuracy limit. About three element evaluations and three n x n
solves per step: some 3-4 times the cost of an explicit step.
"""


import numpy as np

from rbhyst.solve.integrators import N_COEF, Method

KERNEL_ID = 2

#: (8 eps)^2: a Newton correction below 8 ulps of d+ is converged whatever the increment
ROUNDOFF2 = (8.0 * 2.220446049250313e-16) ** 2


def coefficients(mass: np.ndarray, k0: np.ndarray, c: np.ndarray, h) -> np.ndarray:
    """Unused by the step (it needs only M, C and h): zeros of the loop's shape (one set for a
    step h, one per step for an array of them)."""
    return np.zeros(np.shape(h) + (N_COEF, len(mass), len(mass)))


METHOD = Method(
    name="newmark",
    summary="Newmark average acceleration: implicit, Newton iterations with the VRM tangent",
    order=2,
    explicit=False,
    kernel_id=KERNEL_ID,
    coefficients=coefficients,
)
