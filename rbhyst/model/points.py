"""The motion of a point of the body from that of its mass centre G (seed eqs. 7-8).

With small rotations a body point at x from G moves by u_P = u + theta x x relative to the
support: in the plane, with x = (x1, x2),

    u_P1 = u1 - theta3 x2,    u_P2 = u2 + theta3 x1,

and its total acceleration follows in the same way from the total accelerations of G (at1,
at2) and the angular acceleration alphat3. The terms of second order in theta (the
centripetal x omega^2 and the x theta^2 / 2 of the displacement) are those the seed's
kinematics drop, as everywhere in rbhyst.

Written as u_P = T(x) q, the same matrix gives the generalized load of a force F at the point
(its virtual work F . T q): p = T^T F, the seed's eq. 13 (p3 = -p1 x2P + p2 x1P in the plane).
"""

from __future__ import annotations

import numpy as np

from rbhyst.model.coordinates import PLANE, translations


def _levi_civita(i: int, j: int, k: int) -> float:
    """eps_ijk of the axes 0, 1, 2."""
    return float((i - j) * (j - k) * (k - i) / 2)


def point_matrix(x, coordinates=PLANE) -> np.ndarray:
    """(directions, n) T(x) with u_P = T q (eqs. 7-8): a row per translation of q (its axis, in
    the order of q), x the point's coordinates from G (m, as many as the space has)."""
    x3 = np.zeros(3)
    x3[:len(x)] = np.asarray(x, dtype=float)
    rows = translations(coordinates)
    out = np.zeros((len(rows), len(coordinates)))
    for r, i in enumerate(rows):
        out[r, i] = 1.0
        ai = coordinates[i].axis - 1
        for j, c in enumerate(coordinates):
            if c.rotation and c.axis - 1 != ai:
                # (theta_j e_j x x) along e_i = eps_{i j k} x_k, k the third axis
                aj = c.axis - 1
                k = 3 - ai - aj
                out[r, j] = _levi_civita(ai, aj, k) * x3[k]
    return out


def point_columns(name: str, coordinates=PLANE) -> tuple[str, ...]:
    """A point's columns in time_history.csv: its displacement along every translation of q,
    then its total acceleration along each (``top_u1_m, top_u2_m, top_at1_m_s2, top_at2_m_s2``)."""
    moving = [coordinates[i] for i in translations(coordinates)]
    return tuple(f"{name}_{c.column('d')}" for c in moving) + tuple(f"{name}_{c.column('at')}" for c in moving)


def point_motion(d: np.ndarray, at: np.ndarray, x, out: np.ndarray | None = None, coordinates=PLANE) -> np.ndarray:
    """(n, 2 m) the point's displacements and total accelerations along its m directions, given
    G's (n, len(q)) relative displacements (u1, u2, theta3 in the plane) and total
    accelerations (at1, at2, alphat3); x: the point from G (m)."""
    t = point_matrix(x, coordinates)
    rows = translations(coordinates)
    spin = [j for j, c in enumerate(coordinates) if c.rotation]
    m = len(rows)
    if out is None:
        out = np.empty((len(d), 2 * m))
    for r, i in enumerate(rows):
        for src, col in ((d, r), (at, m + r)):
            out[:, col] = src[:, i]
            for j in spin:
                # u1 + theta3 (-x2) is u1 - theta3 x2 to the bit
                out[:, col] += src[:, j] * t[r, j]
    return out
