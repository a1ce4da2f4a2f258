"""Chang's explicit method (CEM), gamma = 1/2, beta = 1/4 (Chang 2002, 2007).

    D = M + dt/2 C + dt^2/4 K0,  B1 = D^-1 (M + dt/2 C),  B2 = D^-1 M / 2
    d+ = d + dt B1 v + dt^2 B2 a
    (M + dt/2 C) a+ = p+ - R(d+) - C (v + dt/2 a);  v+ = v + dt/2 (a + a+)

Explicit (no iterations), unconditionally stable while the tangent stiffness
stays at or below K0, and on a linear system with K = K0 identical to Newmark's
average acceleration method. The seed's explicit method ([14]) is of this family.

Order 2 (displacement and velocity). No numerical dissipation on linear systems
(spectral radius 1). Stiffening beyond K0 (k = delta k0, delta > 1) is stable only
for omega_0 dt < 2 / sqrt(delta - 1); the loop's stiffness monitor keeps
omega_max dt within its limit. Viscous damping enters the acceleration solve
(M + dt/2 C), so it limits no step.
"""

import numpy as np

from rbhyst.solve.integrators import N_COEF, Method

KERNEL_ID = 0
# coefficient slots
B1, B2, MC_INV = 0, 1, 2


def coefficients(mass: np.ndarray, k0: np.ndarray, c: np.ndarray, h) -> np.ndarray:
    """(N_COEF, n, n) for a step h, or (len(h), N_COEF, n, n) for an array of them."""
    h = np.asarray(h, dtype=float)[..., None, None]
    m = np.diag(mass)
    mc = m + 0.5 * h * c
    d = mc + 0.25 * h * h * k0
    out = np.zeros(h.shape[:-2] + (N_COEF, len(mass), len(mass)))
    out[..., B1, :, :] = np.linalg.solve(d, mc)
    out[..., B2, :, :] = 0.5 * np.linalg.solve(d, np.broadcast_to(m, d.shape))
    out[..., MC_INV, :, :] = np.linalg.inv(mc)
    return out


METHOD = Method(
    name="chang",
    summary="Chang's explicit method: unconditionally stable up to K0, no iterations",
    order=2,
    explicit=True,
    kernel_id=KERNEL_ID,
    structure_dependent=True,
    coefficients=coefficients,
)
