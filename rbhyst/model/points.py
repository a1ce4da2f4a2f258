"""The motion of a point of the body from that of its mass centre G (seed eqs. 7-8).

With small rotations a body point at x = (x1, x2) from G moves by

    u_P1 = u1 - theta3 x2,    u_P2 = u2 + theta3 x1

relative to the support, and its total acceleration follows in the same way from the
total accelerations of G (at1, at2) and the angular acceleration alphat3. The terms of
second order in theta3 (the centripetal x omega^2 and the x theta^2 / 2 of the
displacement) are those the seed's kinematics drop, as everywhere in rbhyst.
"""

from __future__ import annotations

import numpy as np

#: a point's columns in time_history.csv, after its name and an underscore
POINT_COLUMNS = ("u1_m", "u2_m", "at1_m_s2", "at2_m_s2")


def point_columns(name: str) -> tuple[str, ...]:
    return tuple(f"{name}_{c}" for c in POINT_COLUMNS)


def point_motion(d: np.ndarray, at: np.ndarray, x, out: np.ndarray | None = None) -> np.ndarray:
    """(n, 4) u_P1, u_P2, at_P1, at_P2 of the point x (m, from G) given G's (n, 3) relative
    displacements (u1, u2, theta3) and total accelerations (at1, at2, alphat3)."""
    x1, x2 = float(x[0]), float(x[1])
    if out is None:
        out = np.empty((len(d), 4))
    out[:, 0] = d[:, 0] - d[:, 2] * x2
    out[:, 1] = d[:, 1] + d[:, 2] * x1
    out[:, 2] = at[:, 0] - at[:, 2] * x2
    out[:, 3] = at[:, 1] + at[:, 2] * x1
    return out
