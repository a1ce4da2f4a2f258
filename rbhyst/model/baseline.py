"""A support acceleration's velocity and displacement, and the correction that brings it to rest.

The analysis takes a record as linear between its samples, so its velocity and displacement are
exact integrals of that. ``to_rest`` subtracts e(t) (c0 + c1 tau + c2 tau^2 + c3 tau^3), tau =
t / T, e an envelope that is 0 where the record must stay as it is (its ends), with the c that
make the final velocity and displacement zero and, within that, the displacement history least
(a constrained least-squares problem): the support ends where it started, at rest, to rounding.
Made motions (rbhyst.analyses.qualification.matching) and random vibration
(rbhyst.model.random_vibration) both end so.
"""

from __future__ import annotations

import numpy as np


def integrate(acc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement from rest of an acceleration linear between its samples (exact)."""
    v = np.concatenate([[0.0], np.cumsum(0.5 * dt * (acc[:-1] + acc[1:]))])
    d = np.concatenate([[0.0], np.cumsum(dt * v[:-1] + dt * dt * (acc[:-1] / 3.0 + acc[1:] / 6.0))])
    return v, d


def to_rest(acc: np.ndarray, dt: float, env: np.ndarray) -> np.ndarray:
    """acc less e(t) (c0 + c1 tau + c2 tau^2 + c3 tau^3): final velocity and displacement zero,
    the displacement history least squares within that."""
    n = len(acc)
    tau = np.arange(n) / (n - 1)
    basis = np.array([env * tau**k for k in range(4)])
    v0, d0 = integrate(acc, dt)
    vb, db = zip(*(integrate(b, dt) for b in basis))
    D = np.array(db).T  # (n, 4): the displacement of each basis function
    C = np.array([[v[-1] for v in vb], [d[-1] for d in db]])
    # c = c_p + N z: c_p meets the end conditions, N spans what keeps them; z minimises the drift
    c_p = np.linalg.lstsq(C, np.array([v0[-1], d0[-1]]), rcond=None)[0]
    null = np.linalg.svd(C)[2][2:].T
    z = np.linalg.lstsq(D @ null, d0 - D @ c_p, rcond=None)[0]
    return acc - (c_p + null @ z) @ basis
