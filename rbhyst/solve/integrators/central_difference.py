"""Classic central difference in velocity form (explicit Newmark, gamma = 1/2, beta = 0).

    d+ = d + dt v + dt^2/2 a
    (M + dt/2 C) a+ = p+ - R(d+) - C (v + dt/2 a);  v+ = v + dt/2 (a + a+)

Stable for omega_max dt < 2 whatever the damping (it enters the acceleration solve);
the same step as Chang's method with K0 = 0.
Order 2; no numerical dissipation within its stability limit (spectral radius 1),
period shortening of order (omega dt)^2 / 24.
"""

import numpy as np

from rbhyst.solve.integrators import N_COEF, Method
from rbhyst.solve.integrators.chang import B1, B2, MC_INV

KERNEL_ID = 1


def coefficients(mass: np.ndarray, k0: np.ndarray, c: np.ndarray, h) -> np.ndarray:
    """(N_COEF, n, n) for a step h, or (len(h), N_COEF, n, n) for an array of them."""
    h = np.asarray(h, dtype=float)[..., None, None]
    eye = np.eye(len(mass))
    out = np.zeros(h.shape[:-2] + (N_COEF, len(mass), len(mass)))
    out[..., B1, :, :] = eye
    out[..., B2, :, :] = 0.5 * eye
    out[..., MC_INV, :, :] = np.linalg.inv(np.diag(mass) + 0.5 * h * c)
    return out


METHOD = Method(
    name="central-difference",
    summary="classic central difference: explicit, stable for omega_max dt < 2",
    order=2,
    explicit=True,
    kernel_id=KERNEL_ID,
    coefficients=coefficients,
)
