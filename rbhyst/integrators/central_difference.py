"""Classic central difference in velocity form (explicit Newmark, gamma = 1/2, beta = 0).

    d+ = d + dt v + dt^2/2 a;  M a+ = p+ - R(d+);  v+ = v + dt/2 (a + a+)

Stable for omega_max dt < 2; the same loop as Chang's method with K0 = 0.
Order 2; no numerical dissipation within its stability limit (spectral radius 1),
period shortening of order (omega dt)^2 / 24.
"""

import numpy as np

from .. import kernels
from . import N_COEF, Method


def coefficients(mass: np.ndarray, k0: np.ndarray, h: float) -> np.ndarray:
    c = np.zeros((N_COEF, 3, 3))
    c[0] = np.eye(3)
    c[1] = 0.5 * np.eye(3)
    return c


METHOD = Method(
    name="central-difference",
    summary="classic central difference: explicit, stable for omega_max dt < 2",
    order=2,
    explicit=True,
    kernel_id=kernels.CENTRAL_DIFFERENCE,
    coefficients=coefficients,
)
