"""The static equilibrium under gravity, reached along the elements' branches from their virgin state.

The weight W (m (g1, g2, 0) in the plane: a generalized load, one entry per coordinate) acts at G. It is applied in increments of W / INCREMENTS; at each,
Newton iterations with the elements' closed-form tangents (seed eq. 16) solve R(q) = lambda W,
every element advancing along its VRM branch from where the previous increment left it (eq. 14
from the committed state): a quasi-static path with no dynamic drop, exact for the VRM up to the
iterations' tolerance, and leaving each element's branch memory where the dynamic run picks it
up. The displacements a run reports are measured from this equilibrium (seed section 2.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rbhyst.solve.kernels import layout as kernels
from rbhyst.solve.kernels.layout import SPATIAL
from rbhyst.errors import AnalysisError

INCREMENTS = 50
MAX_ITERATIONS = 50
#: converged when the out-of-balance force is below this fraction of the weight
TOLERANCE = 1e-13


@dataclass(frozen=True)
class Static:
    q: np.ndarray  # (n,) the coordinates of G at equilibrium (u1, u2, theta3), from the virgin state
    st: np.ndarray  # (rows, 6) element-row states there (U, F, S, G, K, A)
    r: np.ndarray  # (n,) the elements' resultant there: the load that holds the body at rest
    residual: float  # |W - R| / |W|
    iterations: int


def static_equilibrium(system) -> Static:
    """Equilibrium under system.weight (see the module docstring); AnalysisError where the elements
    cannot carry it (their tangent stiffness vanishes or Newton does not converge)."""
    from rbhyst.model.hysteresis import virgin_tangent
    from rbhyst.solve.kernels.compiled import kernel

    update = kernel("static_update")  # (built at install: a run under gravity loads no numba)
    w = np.asarray(system.weight, dtype=float)
    bvec = np.ascontiguousarray(system.bvec, dtype=float)
    params = system.kernel_params  # (stops bear the weight too: a body resting on its contacts)
    mult = np.ascontiguousarray(system.mult, dtype=float)
    ne, n = bvec.shape
    axial = np.ascontiguousarray(system.kernel_axial, dtype=float)
    rot = int(system.rotation_index)
    out = np.zeros(3)
    bq = bvec.copy()  # the rows at q (exact kinematics)
    st = np.zeros((2, ne, kernels.N_STATE))
    for e in range(ne):
        st[0, e, kernels.K] = max(virgin_tangent(params[e, :2], 1.0), virgin_tangent(params[e, :2], -1.0))
    kpeak = np.zeros((ne, 2))
    cur = 0
    q = np.zeros(n)
    scale = max(float(np.max(np.abs(w))), 1e-300)
    total = 0
    r = np.zeros(n)
    for k in range(1, INCREMENTS + 1):
        target = w * (k / INCREMENTS)
        for it in range(MAX_ITERATIONS):
            r = np.zeros(n)
            update(bvec, axial, rot, mult, params, np.ascontiguousarray(q, dtype=float), st, cur, kpeak, r, bq, out)
            ok, bad, kgeo = out[0] == 1.0, int(out[1]), out[2]
            if not ok:
                raise AnalysisError(f"static equilibrium under gravity: element row {bad + 1} left its calibrated "
                                    "range (exp overflow): the elements cannot carry the weight")
            res = target - r
            total += 1
            if np.max(np.abs(res)) <= TOLERANCE * scale:
                break
            kt = (bq.T * (mult * (kpeak[:, 1] + touching(params, st[1 - cur])))) @ bq
            if rot >= 0:
                kt[rot, rot] += kgeo
            # (in space, exact: rows for a turn in the body's axes; the forces' geometric stiffness
            # left out of the Jacobian, so the iterations converge linearly, to the same tolerance)
            try:
                dq = np.linalg.solve(kt, res)
            except np.linalg.LinAlgError:
                dq = np.full(n, np.nan)
            if not np.all(np.isfinite(dq)):
                raise AnalysisError(f"static equilibrium under gravity: at {k / INCREMENTS:.0%} of the weight the "
                                    "elements' tangent stiffness is singular: they cannot carry it")
            q = q + dq if rot != SPATIAL else _turned(q, dq)
        else:
            raise AnalysisError(f"static equilibrium under gravity: Newton iterations did not converge at "
                                f"{k / INCREMENTS:.0%} of the weight (out of balance {np.max(np.abs(res)):.3g} N): "
                                "the elements cannot carry it")
        cur = 1 - cur  # the trial state becomes the committed one
    return Static(q=q, st=st[cur].copy(), r=r, residual=float(np.max(np.abs(w - r)) / scale), iterations=total)


def touching(params: np.ndarray, st: np.ndarray) -> np.ndarray:
    """(rows,) the loading stiffness K of each stop met exactly at its gap, bearing nothing yet (a
    contact touching the ground at rest): Newton's matrix takes it, as the stop takes it from
    there on (rbhyst.model.stop); 0 elsewhere."""
    from rbhyst.model.hysteresis import STOP_K, STOP_LOWER, STOP_ROW, STOP_UPPER

    if params.shape[1] <= STOP_ROW:
        return np.zeros(len(st))
    p = params[:, STOP_ROW]
    u = st[:, kernels.U]
    at_gap = ((u == p[:, STOP_LOWER]) | (u == p[:, STOP_UPPER])) & (st[:, kernels.FS] == 0.0)
    return np.where(at_gap, p[:, STOP_K], 0.0)


def _turned(q: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """q + dq for a body in space with exact kinematics: the turn dq[3:6] (body axes) composed on
    the attitude (rbhyst.model.rotations)."""
    from rbhyst.model.rotations import matrices, rotation_vectors

    out = q + dq
    out[3:6] = rotation_vectors(matrices(q[3:6]) @ matrices(dq[3:6]))[0]
    return out


def at_rest_under_gravity(system):
    """The system with its static equilibrium found and the weight in its load (no weight: itself)."""
    if system.weight is None or system.static is not None:
        return system
    from dataclasses import replace

    st = static_equilibrium(system)
    # the load that holds the body exactly at rest there is the elements' resultant (the
    # weight to within the iterations' 1e-13): without excitation, rest stays rest to the bit
    held = st.r
    if system.rotation_index == SPATIAL:  # the kernels take a load's moments in the ground's axes
        from rbhyst.model.rotations import matrices

        held = np.concatenate([st.r[:3], matrices(st.q[3:6])[0] @ st.r[3:6]])
    return replace(system, static=st, excitation=replace(system.excitation, constant=tuple(map(float, held))))
