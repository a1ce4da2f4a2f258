"""The kinematics of a body in space, six coordinates (rbhyst.model.system.assemble_space builds its System).

q = (u1, u2, u3, theta1, theta2, theta3): the translations of the mass centre G and its small
rotations about the deck's axes (a vector, theta). A body point at r from G moves by
u + theta x r; an element along the unit direction d at r deforms by d . (u + theta x r) =
b . q with b = (d, r x d), and its force f acts back on the body as b f (force d f, moment
r x d f about G). M = diag(m, m, m, J) with J the inertia tensor about G.

The compiled kernels take a diagonal M. Where J is not diagonal the body runs in its principal
axes: J = P diag(Jp) P^T, the kernels' rotations phi = P^T theta, their rows b_phi = P^T b_theta
and loads likewise, and System.frame = diag(I, P) turns every output back (history.Layout):
small rotations about the deck's axes are a vector, so the change of axes is exact. Where J is
diagonal as given, P = I and nothing changes.
"""

from __future__ import annotations

import numpy as np

from rbhyst.model.solid import Solid

#: the signals of a body in space and their deck keys
SUPPORT_KEYS = {"ag1": "x1", "ag2": "x2", "ag3": "x3"}
FORCE_KEYS = ("p1", "p2", "p3", "m1", "m2", "m3")


def row(x, direction) -> np.ndarray:
    """b = (d, r x d) of an element along ``direction`` (unit) at x (from G): its deformation is
    b . q, the motion of its point along d."""
    d = np.asarray(direction, dtype=float)
    return np.concatenate([d, np.cross(np.asarray(x, dtype=float), d)])


def unit(direction) -> np.ndarray:
    """The line of action, normalised (the deck has refused a zero vector)."""
    d = np.asarray(direction, dtype=float)
    return d / np.linalg.norm(d)


#: products of inertia below this share of the largest moment are rounding (a box's computed
#: from its hull's tetrahedra carries some 1e-16): the tensor counts as diagonal
DIAGONAL = 1e-12


def principal_frame(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(the diagonal of J in the kernels' axes, the frame diag(I, P) or None where J is diagonal as
    given, to within DIAGONAL). P's columns are the principal axes, each the one nearest a deck
    axis in turn and pointing along it where it can, right-handed (det P = +1)."""
    j = np.asarray(inertia, dtype=float)
    off = j - np.diag(np.diag(j))
    if not np.any(np.abs(off) > DIAGONAL * float(np.max(np.abs(np.diag(j))))):
        return np.diag(j).copy(), None
    lam, vec = np.linalg.eigh(j)
    order, free = [], [0, 1, 2]
    for axis in range(3):  # the principal axis nearest x1, then x2's among the rest
        k = max(free, key=lambda c: abs(vec[axis, c]))
        order.append(k)
        free.remove(k)
    lam, p = lam[order], vec[:, order]
    p = p * np.where(np.diag(p) < 0.0, -1.0, 1.0)
    if np.linalg.det(p) < 0.0:
        p[:, 2] = -p[:, 2]
    frame = np.eye(6)
    frame[3:, 3:] = p
    return lam, frame


def free_motions(bvec: np.ndarray, body: Solid, frame: np.ndarray | None) -> list[str]:
    """Each rigid motion no element resists (B q = 0), described in the deck's axes."""
    size = body.extent or 1.0
    scale = np.array([1.0, 1.0, 1.0, 1.0 / size, 1.0 / size, 1.0 / size])
    _, sv, vt = np.linalg.svd(bvec * scale, full_matrices=True)
    sv = np.concatenate([sv, np.zeros(6 - len(sv))])
    out = []
    for k in range(6):
        if sv[k] > 1e-9 * max(sv[0], 1e-300):
            continue
        q = vt[k] * scale
        q = q if frame is None else frame @ q
        u, th = q[:3], q[3:]

        def vec(v):
            v = v / np.max(np.abs(v))
            return "(" + ", ".join(f"{x + 0.0:.4g}" for x in np.where(np.abs(v) < 1e-9, 0.0, v)) + ")"

        if np.linalg.norm(th) * size < 1e-9 * np.linalg.norm(u):
            out.append(f"translation along {vec(u)}")
        else:
            c = np.cross(th, u) / float(th @ th) + body.mass_centre  # the axis's point nearest G, deck frame
            out.append(f"rotation about the axis {vec(th)} through ({', '.join(f'{x + 0.0:.4g}' for x in c)}) m")
    return out
