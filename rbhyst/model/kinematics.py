"""Exact planar kinematics of the rigid body: rotations of any size, in numpy.

The seed linearises the motion of a body point in theta3 (eqs. 7-8). With exact kinematics a
point at r from G (in the body at rest) is at x_G + R(theta) r, R the rotation by theta about
x3, and moves by

    u_P = u_G + (R(theta) - I) r.

Each element keeps the line of action it has at rest, fixed in the ground (as the seed draws
it from its support, and as a mount's base holds it): it deforms by the displacement of its
body point along that line, d . u_P, and its force acts along d at the point's current place:

    u_e = d1 u1 + d2 u2 + b3 sin(theta) + c (cos(theta) - 1),
    b3 = d . (k x r) = r1 d2 - r2 d1 (the seed's row), c = d . r (the axial offset),

whose derivative b_e(q) = (d1, d2, b3 cos(theta) - c sin(theta)) carries the element's force
back to G (virtual work: the moment about G of the force at the turned point is exact). To
first order in theta these are the seed's u_e = b . q. The mass matrix about G stays
diag(m, m, J): in the plane there is no gyroscopic term. The compiled kernels carry the same
formulas (rbhyst.solve.kernels.elements.update_elements).
"""

from __future__ import annotations

import numpy as np

#: the kernels' code for a body in space with exact kinematics (rbhyst.solve.kernels.layout.SPATIAL)
SPATIAL = -2


def rows_at(bvec: np.ndarray, axial: np.ndarray | None, rot: int, q: np.ndarray) -> np.ndarray:
    """(ne, n) the rows b_e(q) = du_e/dq at the configuration q (n,): the seed's b_e where the
    kinematics are small (rot = -1); a body in space, exact (rot = -2): rbhyst.model.rotations."""
    if rot == SPATIAL:
        from rbhyst.model.rotations import space_rows

        return space_rows(bvec, axial, np.asarray(q, dtype=float)[3:6])
    rows = np.array(bvec, dtype=float, copy=True)
    if rot >= 0:
        th = float(q[rot])
        rows[:, rot] = bvec[:, rot] * np.cos(th) - axial * np.sin(th)
    return rows


def turned(x, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R(theta) x) for the point x (2,) from G at every rotation theta (k,): its two components."""
    c, s = np.cos(theta), np.sin(theta)
    return c * x[0] - s * x[1], s * x[0] + c * x[1]


def point_motion_exact(d: np.ndarray, v: np.ndarray, at: np.ndarray, x, theta: np.ndarray,
                       origin_theta: float = 0.0, out: np.ndarray | None = None) -> np.ndarray:
    """(k, 4) a body point's displacements u_P1, u_P2 and total accelerations at_P1, at_P2.

    d: (k, 3) G's displacements (u1, u2, and the rotation measured from the start), v (k, 3) its
    velocities, at (k, 3) its total accelerations (at1, at2, alphat3); theta (k,) the rotation
    from the body at rest (the start plus d[:, 2]); x the point from G at rest (m). The point's
    displacement is measured from where it is at the start (rotation origin_theta):
    u_P = u_G + (R(theta) - R(theta0)) x, and a_P = a_G + alpha k x (R x) - omega^2 (R x).
    """
    x = np.asarray(x, dtype=float)
    if out is None:
        out = np.empty((len(d), 4))
    r1, r2 = turned(x, theta)
    o1, o2 = turned(x, np.array([origin_theta]))
    w2 = v[:, 2] * v[:, 2]
    out[:, 0] = d[:, 0] + (r1 - o1[0])
    out[:, 1] = d[:, 1] + (r2 - o2[0])
    out[:, 2] = at[:, 0] - at[:, 2] * r2 - w2 * r1
    out[:, 3] = at[:, 1] + at[:, 2] * r1 - w2 * r2
    return out


def turned_loads(p: np.ndarray, theta, n: int, rot: int) -> np.ndarray:
    """(k, n) generalized loads from the load columns p (k, width) at the rotations theta (k,):
    where the forces' arm turns (width n + 2: r x p and r . p follow), the moment is
    cos(theta) (r x p) - sin(theta) (r . p) (rbhyst.model.system.Excitation.follow)."""
    out = np.array(p[:, :n], dtype=float, copy=True)
    if p.shape[1] > n and rot >= 0:
        half = np.sin(0.5 * np.asarray(theta, dtype=float))
        out[:, rot] += -2.0 * half * half * p[:, n] - np.sin(theta) * p[:, n + 1]
    return out


def loads_at(p: np.ndarray, q: np.ndarray, n: int, rot: int, axial: np.ndarray | None = None) -> np.ndarray:
    """(k, n) generalized loads from the load columns p (k, width) at the configurations q (k, n)
    as the kernels take them: the plane's turned arm (``turned_loads``), or in space with exact
    kinematics the moments in the body's axes (rbhyst.model.rotations.body_loads)."""
    q = np.asarray(q, dtype=float)
    if rot == SPATIAL:
        from rbhyst.model.rotations import body_loads

        return body_loads(p, np.broadcast_to(q[..., 3:6], (len(p), 3)), n, axial)
    theta = np.broadcast_to(q[..., rot] if rot >= 0 else np.zeros(1), (len(p),))
    return turned_loads(p, theta, n, rot)


def exact_twin(system):
    """The same scene with exact kinematics: each kernel row split where its elements' points lie
    differently along their line of action (they deform alike only to first order), before
    any static equilibrium (the exact one differs). None for a body that is neither the plane's
    nor one in space (exact kinematics are built for those)."""
    from dataclasses import replace

    from rbhyst.model.coordinates import PLANE, SPACE
    from rbhyst.model.system import arm_turns, axial_offset

    if system.coordinates not in (PLANE, SPACE):
        return None
    if system.kinematics == "exact":
        return system
    if system.coordinates == SPACE:
        return _exact_twin_space(system)
    elements, mult, old, arms = _split_rows(system, lambda el: axial_offset(el.x[0], el.x[1],
                                                                           np.radians(el.angle_deg)))
    excitation = replace(system.excitation, follow=arm_turns(system.excitation))
    return _twin(system, elements, mult, old, excitation, np.array(arms))


def _split_rows(system, arm_of):
    """The elements regrouped into rows that deform alike with exact kinematics: those of a row
    whose ``arm_of`` (their offset along their line in the plane, point and line in space) differ
    part. Returns (the elements renumbered, each row's multiplicity, its old row, its arm)."""
    from dataclasses import replace

    keys, rows, elements = {}, [], []
    for el in system.elements:
        arm = arm_of(el)
        key = (el.row, *np.round(np.atleast_1d(arm) / 1e-12).astype(np.int64).tolist())
        if key not in keys:
            keys[key] = len(rows)
            rows.append((el.row, arm))
        elements.append(replace(el, row=keys[key]))
    mult = np.zeros(len(rows))
    for el in elements:
        mult[el.row] += el.count
    return elements, mult, [r for r, _ in rows], [a for _, a in rows]


def _twin(system, elements, mult, old, excitation, axial):
    """The exact twin of ``system`` with its rows regrouped (_split_rows), before any static
    equilibrium (the weight enters again with the exact one)."""
    from dataclasses import replace

    if system.static is not None:
        excitation = replace(excitation, constant=(0.0,) * system.n)
    return replace(system, bvec=system.bvec[old], mult=mult, params=system.params[old], k0=system.k0[old],
                   k_reversal=system.k_reversal[old], elements=tuple(elements), static=None, excitation=excitation,
                   kinematics="exact", axial=axial)


def _exact_twin_space(system):
    """exact_twin of a body in space: rows split where their points or lines differ (each row's
    point and line in the kernels' rotation axes, then the force point, rbhyst.model.rotations)."""
    from dataclasses import replace

    from rbhyst.model.system import arm_turns, space_turning

    p = np.eye(3) if system.frame is None else np.asarray(system.frame)[3:, 3:]
    elements, mult, old, arms = _split_rows(system, lambda el: np.concatenate(
        [np.asarray(el.x, dtype=float) @ p, np.asarray(el.direction, dtype=float) @ p]))
    excitation = system.excitation
    if arm_turns(excitation):
        excitation = replace(excitation, follow=True, turning=space_turning(p))
    axial = np.concatenate(arms + [p.T @ np.asarray(system.excitation.point, dtype=float)])
    return _twin(system, elements, mult, old, excitation, axial)


def damper_rows(system, q: np.ndarray) -> np.ndarray:
    """(k, dampers, n) each [[dampers]] entry's row b_d(q) at the configurations q (k, n), in the
    kernels' axes: the plane's (b1, b2, b3 cos(theta) - c sin(theta)), in space (d, x' x R^T d')
    (rbhyst.solve.kernels.elements.turned_dampers); the rows at rest with small rotations."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    rest = np.array([dp.b for dp in system.dampers], dtype=float).reshape(-1, system.n)
    rows = np.broadcast_to(rest, (len(q),) + rest.shape).copy()
    rot = system.rotation_index
    if system.kinematics != "exact" or not len(rest):
        return rows
    data = system.kernel_damping[system.n:]
    if rot == SPATIAL:
        from rbhyst.model.rotations import matrices

        x, c = data[0::2, 3:6], data[1::2, :3]
        a = np.einsum("kji,dj->kdi", matrices(q[:, 3:6]), c)  # R^T d'
        rows[:, :, 3:] = np.cross(x[None], a)
        return rows
    th = q[:, rot][:, None]
    rows[:, :, rot] = rest[None, :, rot] * np.cos(th) - data[1::2, 0][None] * np.sin(th)
    return rows
