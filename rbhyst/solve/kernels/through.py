"""A whole run stepped again in one call: the error estimate's companion and its probe.

The run itself goes through the loop a chunk at a time (kernels.loop), its rows passing
through Python's reductions and writers between the calls. The companion and its probe
(rbhyst.solve.companion) step the same grid again, each step at the substep level the run
took, and keep only arrays: here every segment of equal splitting is one call of the same
loop, and the rows go where the caller says (a row at every compute node, or the compared
nodes picked from each segment's rows), with no Python between the segments.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rbhyst.solve.kernels.loop import run_chunk


@njit(cache=True, error_model="numpy", _nrt=False)
def step_through(method, coefs, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt, load, segments, dt,
                 omega_dt_limit, max_level, newton_tol, newton_max_iter, x, st, st_save, kpeak, bq, w, wm,
                 out_d, out_v, out_u, out_f, out_e, out_fb, whole, take, pick_d, pick_v, pick_f, levels, force, info):
    """Advance the state x, st through every segment, each compute step at the level ``levels``
    holds where ``force`` (a step is split further only where Newton's iterations fail), else
    as the stiffness monitor judges (run_chunk's ``force``).

    segments (k, 5): each run of equal splitting's first output step, output steps, compute
    steps each (nsub), its coefficients' index in ``coefs`` and the least substep level (the
    plan's level0); load (nodes, width): the load at every compute node from t = 0; h_c = dt
    / nsub, a segment's start dt * first (as the plan's chunks take them, to the bit).
    out_d, out_v, out_u, out_f: the rows after every compute step, each an array of every
    node (``whole``[0..3] true: row k + 1 after step k, row 0 the caller's) or one segment's
    scratch (row 0 after its first step); out_e and out_fb scratch. take (m,): compute nodes
    (ascending, > 0) whose d, v and f go to rows 1.. of pick_d, pick_v, pick_f. With rot =
    LOCATED a row's force patched by the next step (run_chunk) is kept across a segment's start
    only in an out_f of every node (the companion keeps it so, or re-drives its forces).
    The arguments between them are run_chunk's. Returns the compute steps taken (all of them,
    unless info says how the loop failed)."""
    node = 0
    p = 0
    every = np.int64(1)  # (a row after every compute step; typed as run_chunk's own call types it, not
    # as the literal 1, which would compile the loop a second time)
    for s in range(segments.shape[0]):
        first, n_out, nsub, ci, level0 = segments[s, 0], segments[s, 1], segments[s, 2], segments[s, 3], segments[s, 4]
        steps = n_out * nsub
        a, b = (node + 1, node + 1 + steps)
        d = out_d[a:b] if whole[0] else out_d[:steps]
        v = out_v[a:b] if whole[1] else out_v[:steps]
        u = out_u[a:b] if whole[2] else out_u[:steps]
        f = out_f[a:b] if whole[3] else out_f[:steps]
        fb = out_f[node] if whole[3] else out_fb
        written = run_chunk(method, coefs[ci], mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt,
                            load[node:node + steps + 1], dt * first, dt / nsub, every, steps, omega_dt_limit, level0,
                            max_level, newton_tol, newton_max_iter, x, st, st_save, kpeak, bq, w, wm,
                            d, v, u, f, out_e[:steps], fb, levels[node:node + steps], force, info)
        if written != steps:
            return node + written
        while p < take.shape[0] and take[p] <= node + steps:
            r = take[p] - a
            for i in range(d.shape[1]):
                pick_d[p + 1, i] = d[r, i]
                pick_v[p + 1, i] = v[r, i]
            for e in range(f.shape[1]):
                pick_f[p + 1, e] = f[r, e]
            p += 1
        node += steps
    return node
