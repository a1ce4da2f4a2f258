"""The stops' share of the kernels' element states (rbhyst.model.stop; their columns in
rbhyst.solve.kernels.layout): the forces the elements carry with them, and a run's record of
impacts."""

from __future__ import annotations

import numpy as np

from rbhyst.solve.kernels import layout as kernels


def element_forces(st: np.ndarray) -> np.ndarray:
    """(rows,) each kernel row's force in the element states st (rows, N_STATE): its VRM's and its
    stop's (the VRM's alone, to the bit, where the stop bears nothing)."""
    f = st[:, kernels.F].copy()
    fs = st[:, kernels.FS]
    bears = fs != 0.0
    f[bears] += fs[bears]
    return f


def stop_record(st: np.ndarray) -> np.ndarray:
    """(rows, 4) each kernel row's stop at the end of a run from its final states st (rows,
    N_STATE): contacts begun, energy its impacts lost (J, one element), largest force (N) and
    penetration (m); a contact still on counts its loss so far."""
    return np.ascontiguousarray(st[:, [kernels.NI, kernels.IMP, kernels.PF, kernels.PD]], dtype=float)
