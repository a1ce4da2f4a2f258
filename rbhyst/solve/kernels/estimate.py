"""The companion's estimate in one compiled call (rbhyst.solve.companion, rbhyst.solve.estimate).

What the error estimate of a fixed-step run does after the run, with no Python between the
parts: the companion's source from the run's rows (kernels.modified.companion_source), the
companion stepped through the run's grid with every turn located (kernels.through), its
forces re-driven where the run split a step (kernels.redrive), its difference from the run at
the compared nodes reduced to every column's largest change (kernels.reduce.largest_change),
and, where that estimate lies between the check's threshold and the largest the companion is
trusted with, the probe: the run again with a fraction of the source added, reduced alike. A
short run's estimate was some forty calls of numpy and of these kernels, each with its arrays
made anew, more time than the two steppings themselves.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rbhyst.solve.kernels.layout import F, LOCATED, U, X_Q
# what companion_estimate returns (named in the layout, which a run reads without numba)
from rbhyst.solve.kernels.layout import ESTIMATE_COMPANION_SPLIT as COMPANION_SPLIT
from rbhyst.solve.kernels.layout import ESTIMATE_DONE as DONE
from rbhyst.solve.kernels.layout import ESTIMATE_FAILED as FAILED
from rbhyst.solve.kernels.layout import ESTIMATE_OUT_OF_RANGE as OUT_OF_RANGE
from rbhyst.solve.kernels.layout import ESTIMATE_PROBE_SPLIT as PROBE_SPLIT
from rbhyst.solve.kernels.layout import ESTIMATE_PROBED as PROBED
from rbhyst.solve.kernels.layout import ESTIMATE_TOO_LARGE as TOO_LARGE
from rbhyst.solve.kernels.modified import companion_source
from rbhyst.solve.kernels.redrive import redrive
from rbhyst.solve.kernels.reduce import largest_change
from rbhyst.solve.kernels.through import step_through


@njit(cache=True, error_model="numpy", _nrt=False)
def _zero(a):
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            a[i, j] = 0.0


@njit(cache=True, error_model="numpy", _nrt=False)
def _step(method, coefs, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt, load, segments, dt, omega_dt_limit,
          max_level, newton_tol, newton_max_iter, x0, st0, v_start, x, st, st_save, kpeak, bq, w, wm, out_d, out_v, out_u,
          out_f, out_e, out_fb, whole, take, pick_d, pick_v, pick_f, levels, taken, force, info):
    """One stepping through every segment from the run's start state x0, st0 with the
    velocity ``v_start`` (plan.step_through's, with its fresh work space): the start row into
    row 0 of the whole arrays and of the picked ones, each step at the run's level. Returns
    whether it went through with the run's levels (a failure: info, and -1)."""
    n = v_start.shape[0]
    for i in range(x0.shape[0]):
        x[i] = x0[i]
    for j in range(n):
        x[X_Q + n + j] = v_start[j]
    for a in range(st0.shape[0]):
        for e in range(st0.shape[1]):
            for k in range(st0.shape[2]):
                st[a, e, k] = st0[a, e, k]
    for k in range(levels.shape[0]):
        taken[k] = levels[k]
    for k in range(info.shape[0]):
        info[k] = 0.0
    _zero(st_save)
    _zero(kpeak)
    _zero(bq)
    _zero(w)
    _zero(wm)
    # the start row (plan.start_row: the run's displacement, at rest, virgin elements)
    for j in range(n):
        d0 = x0[X_Q + j]
        if whole[0]:
            out_d[0, j] = d0
        if whole[1]:
            out_v[0, j] = 0.0
        pick_d[0, j] = d0
        pick_v[0, j] = 0.0
    for e in range(st0.shape[1]):
        if whole[2]:
            out_u[0, e] = st0[0, e, U]
        if whole[3]:
            out_f[0, e] = st0[0, e, F]
        pick_f[0, e] = st0[0, e, F]
    done = step_through(method, coefs, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt, load, segments, dt,
                        omega_dt_limit, max_level, newton_tol, newton_max_iter, x, st, st_save, kpeak, bq, w, wm,
                        out_d, out_v, out_u, out_f, out_e, out_fb, whole, take, pick_d, pick_v, pick_f, taken, force,
                        info)
    if done != levels.shape[0]:
        return -1
    for k in range(levels.shape[0]):
        if taken[k] != levels[k]:
            return 0
    return 1


@njit(cache=True, error_model="numpy", _nrt=False)
def _worst(top, scales, body, expand):
    """The largest of estimate.scaled_errors of the changes ``top`` (its body columns, then
    every kernel row's force, each output element's taken by ``expand``)."""
    worst = 0.0
    for c in range(scales.shape[0]):
        x = top[c] if c < body else top[body + expand[c - body]]
        s = scales[c]
        err = x / s if s > 0.0 else (math.inf if x > 0.0 else 0.0)
        worst = max(worst, err)
    return worst


@njit(cache=True, error_model="numpy", _nrt=False)
def companion_estimate(method, coefs, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt, segments, dt,
                       omega_dt_limit, max_level, newton_tol, newton_max_iter, modified, load, t, levels, d_run,
                       v_run, f_run, a0, x0, st0, rb, c, minv_a, mass_a, k0, bounds, substeps, breaks, every, take,
                       ct, damped_t, back, turned, arms, minv_t, expand, scales, check, largest, eps, extra, offset,
                       a_w, h_w, near_w, load_w, x, st, st_save, kpeak, bq, w, wm, out_d, out_v, out_u, out_f,
                       out_e, out_fb, f_re, whole, pick_d, pick_v, pick_f, picks, dd, dv, df, top_c, top_p, lw, n_w,
                       taken, force, info):
    """The companion's source, the companion and its largest changes (top_c), and where they lie
    between ``check`` and ``largest`` of ``scales`` (estimate.scaled_errors; ``expand`` each
    output element's kernel row), the probe's at ``eps`` (top_p); returns DONE, PROBED or why not.

    The loop's arguments as plan.step_through's (rot: the system's, LOCATED for the
    companion); the run's tap (load, t, levels at every compute node, d_run, v_run, f_run, a0,
    the start state x0, st0) and companion_source's other arguments (modified: the method's
    code, minv_a and mass_a M^-1 and M as arrays, into extra, offset with a_w, h_w, near_w);
    take: the compared nodes (plan.compared_nodes: every ``every``-th compute node from t = 0,
    node 0 first) written here, picks: them after node 0;
    largest_change's arguments (minv_t: the table's M^-1) through dd, dv, df. The rest is work
    space: the companion's rows in out_d, out_v and out_u or out_f (``whole``: every node; its
    forces re-driven into f_re where a step was split), the probe's in the same arrays' first
    rows and in pick_d, pick_v, pick_f.

    Long because it is the whole estimate in one call: every part split off is another set of
    the same arguments passed on, and the parts are a sequence, not a loop to factor."""
    n = v_run.shape[1]
    nodes = t.shape[0]
    ne = f_run.shape[1]
    companion_source(modified, load, v_run, f_run, a0, rb, c, damped, minv_a, mass_a, k0, t, levels, bounds,
                     substeps, dt, breaks, a_w, h_w, near_w, extra, offset, n_w[0], n_w[1], n_w[2])
    # the compared nodes: every ``every``-th compute node (plan.compared_nodes)
    take[0] = 0
    for p in range(1, take.shape[0]):
        take[p] = p * every
        picks[p - 1] = p * every
    if take[take.shape[0] - 1] >= nodes:
        return FAILED
    split = False
    for k in range(levels.shape[0]):
        if levels[k] != 0:
            split = True
    for i in range(nodes):
        for j in range(load.shape[1]):
            load_w[i, j] = load[i, j] + extra[i, j] if j < n else load[i, j]
    for j in range(n):
        n_w[0, j] = -offset[0, j]
    whole[0] = True
    whole[1] = True
    whole[2] = split
    whole[3] = not split
    located = np.int64(LOCATED)  # (a variable: a literal would compile the loop again for it)
    went = _step(method, coefs, mass, minv, cm, damped, bvec, axial, located, mult, params, wgt, load_w, segments,
                 dt, omega_dt_limit, max_level, newton_tol, newton_max_iter, x0, st0, n_w[0], x, st, st_save,
                 kpeak, bq, w, wm, out_d, out_v, out_u, out_f, out_e, out_fb, whole, picks[:0], pick_d, pick_v,
                 pick_f, levels, taken, force, info)
    if went < 0:
        return FAILED
    if went == 0:
        return COMPANION_SPLIT
    if split:
        # the forces with every turn where it falls, between the rows (companion.redriven)
        if redrive(params, st0[0], out_u[:nodes], f_re) >= 0:
            return OUT_OF_RANGE
    f_c = f_re if split else out_f
    for p in range(take.shape[0]):
        node = take[p]
        for j in range(n):
            dd[p, j] = d_run[node, j] - out_d[node, j]
            dv[p, j] = (v_run[node, j] - offset[node, j]) - out_v[node, j]
        for e in range(ne):
            df[p, e] = f_run[node, e] - f_c[node, e]
    largest_change(dd, dv, df, rb, ct, damped_t, minv_t, back, turned, arms, top_c, lw)
    worst = _worst(top_c, scales, top_c.shape[0] - ne, expand)
    if worst > largest:
        return TOO_LARGE
    if not worst > check:
        return DONE
    for i in range(nodes):
        for j in range(load.shape[1]):
            load_w[i, j] = load[i, j] + eps * extra[i, j] if j < n else load[i, j]
    for j in range(n):
        n_w[0, j] = -eps * offset[0, j]
    for k in range(4):
        whole[k] = False
    went = _step(method, coefs, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt, load_w, segments, dt,
                 omega_dt_limit, max_level, newton_tol, newton_max_iter, x0, st0, n_w[0], x, st, st_save, kpeak,
                 bq, w, wm, out_d, out_v, out_u, out_f, out_e, out_fb, whole, picks, pick_d, pick_v, pick_f,
                 levels, taken, force, info)
    if went < 0:
        return FAILED
    if went == 0:
        return PROBE_SPLIT
    for p in range(take.shape[0]):
        node = take[p]
        for j in range(n):
            dd[p, j] = d_run[node, j] - pick_d[p, j]
            dv[p, j] = v_run[node, j] - pick_v[p, j]
        for e in range(ne):
            df[p, e] = f_run[node, e] - pick_f[p, e]
    largest_change(dd, dv, df, rb, ct, damped_t, minv_t, back, turned, arms, top_p, lw)
    return PROBED
