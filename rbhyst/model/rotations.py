"""Exact kinematics of a body in space: finite rotations, in numpy.

The attitude is the rotation vector psi: R = exp([psi]x) (Rodrigues), |psi| the angle turned
about the axis psi / |psi|; theta1..3 of a run with exact kinematics are its components. The
angular velocity the kernels carry is omega in the body's own (principal) axes, so that

    m u'' = p - R_u,    J omega' + omega x J omega = M_b - R_theta,

with M = diag(m, m, m, J) constant (Euler's equations, their gyroscopic term included), and
psi' = J_r(psi)^-1 omega. As in the plane (rbhyst.model.kinematics), each element keeps the
line of action d it has at rest, fixed in the ground, and deforms by its point's exact
displacement along it:

    u_e = d . (u + R x - x),    b_e(q) = (d, x x R^T d)   (rows for (u', omega)),

x its point from G in the body at rest. A load's moments about G (m1..m3, and r_p x p of forces
at a point r_p whose arm turns with the body) enter in the body's axes: R^T m + r_p x R^T p.
The outputs are in the ground's (the deck's) axes: theta = psi, omega_s = R omega, alpha_s = R
omega' (the body's angular acceleration seen from the ground: d(R omega)/dt = R omega' since
omega x omega = 0), the resultant's moment R M_b about G. The compiled kernels carry the same
formulas (rbhyst.solve.kernels.rotations).
"""

from __future__ import annotations

import numpy as np


def matrices(psi: np.ndarray) -> np.ndarray:
    """(k, 3, 3) R = exp([psi]x) of the rotation vectors psi (k, 3) (Rodrigues' formula)."""
    psi = np.atleast_2d(np.asarray(psi, dtype=float))
    t2 = np.einsum("ki,ki->k", psi, psi)
    t = np.sqrt(t2)
    small = t < 1e-4
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / np.where(small, 1.0, t))
        half = np.sin(0.5 * t)
        b = np.where(small, 0.5 - t2 / 24.0, 2.0 * half * half / np.where(small, 1.0, t2))
    k = np.zeros((len(psi), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -psi[:, 2], psi[:, 1], -psi[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = psi[:, 2], -psi[:, 1], psi[:, 0]
    return np.eye(3)[None] + a[:, None, None] * k + b[:, None, None] * (k @ k)


def rotation_vectors(r: np.ndarray) -> np.ndarray:
    """(k, 3) the rotation vectors (|psi| <= pi) of the rotation matrices r (k, 3, 3)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(r, dtype=float).reshape(-1, 3, 3)).as_rotvec()


def split_axial(axial: np.ndarray, ne: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' ``axial`` of a body in space, exact: (points x' (ne, 3), lines d' (ne, 3), in
    the kernels' rotation axes, and the force point r_p (3,))."""
    rows = np.asarray(axial[:6 * ne], dtype=float).reshape(ne, 6)
    return rows[:, :3], rows[:, 3:], np.asarray(axial[6 * ne:6 * ne + 3], dtype=float)


def space_rows(bvec: np.ndarray, axial: np.ndarray, psi) -> np.ndarray:
    """(ne, 6) the rows b_e(q) = (d, x' x R^T d') at the attitude psi (3,)."""
    x, c, _ = split_axial(axial, len(bvec))
    rt = matrices(psi)[0].T
    rows = np.array(bvec, dtype=float, copy=True)
    rows[:, 3:] = np.cross(x, c @ rt.T)
    return rows


def body_loads(p: np.ndarray, psi: np.ndarray, n: int, axial: np.ndarray) -> np.ndarray:
    """(k, n) the loads p (k, width) with their moments in the body's axes at the attitudes psi
    (k, 3): R^T m, and where forces act away from G (columns n..n+2) r_p x R^T f for r_p x f."""
    out = np.array(p[:, :n], dtype=float, copy=True)
    rt = np.transpose(matrices(psi), (0, 2, 1))
    m = out[:, 3:6]
    if p.shape[1] > n:
        rp = np.asarray(axial[-3:], dtype=float)
        f = p[:, n:n + 3]
        m = m - np.cross(rp, f)
        out[:, 3:6] = np.einsum("kij,kj->ki", rt, m) + np.cross(rp, np.einsum("kij,kj->ki", rt, f))
    else:
        out[:, 3:6] = np.einsum("kij,kj->ki", rt, m)
    return out


def body_rows(bvec: np.ndarray, axial: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """(k, ne, 3) each row's rotation entries x' x R^T d' at the attitudes psi (k, 3)."""
    x, c, _ = split_axial(axial, len(bvec))
    rt = np.transpose(matrices(psi), (0, 2, 1))
    a = np.einsum("kij,ej->kei", rt, c)
    return np.cross(x[None], a)


def gyroscopic(mass: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """(k, 3) omega x J omega, J = diag(mass[3:6]) (the principal axes)."""
    return np.cross(omega, omega * np.asarray(mass, dtype=float)[3:6])


def point_motion_space(d: np.ndarray, at: np.ndarray, omega: np.ndarray, x, origin, out=None) -> np.ndarray:
    """(k, 6) a body point's displacements u_P1..3 and total accelerations at_P1..3, exact.

    d: (k, 6) G's displacements and the rotation vectors psi (the deck's axes), at (k, 6) its
    total accelerations (the body's angular acceleration seen from the ground in at[:, 3:]),
    omega (k, 3) its angular velocity in the ground's axes; x the point from G at rest;
    origin (3, 3) the attitude its displacement is measured from (the static equilibrium's):
    u_P = u_G + (R - R0) x, a_P = a_G + alpha x (R x) + omega x (omega x R x).
    """
    x = np.asarray(x, dtype=float)
    if out is None:
        out = np.empty((len(d), 6))
    rx = matrices(d[:, 3:6]) @ x
    out[:, :3] = d[:, :3] + rx - origin @ x
    out[:, 3:] = at[:, :3] + np.cross(at[:, 3:6], rx) + np.cross(omega, np.cross(omega, rx))
    return out
