"""The time-stepping loop shared by every fixed-step method, one chunk of output steps at a time.

Each compute step is checked against the stiffest mode it has to resolve: the loop halves
the step (the load interpolated linearly) until ``omega_max * h <= omega_dt_limit`` or the
substep level runs out. The loop's running state (x: displacement, velocity, acceleration,
energies, counters; st: the element states) is carried from one call to the next, so that
a run of any length keeps only one chunk of rows in memory.
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.solve.integrators.steps import take_step
from rbhyst.solve.kernels.layout import (E_HYST, E_IN, E_KIN, E_VISC, F, I_BRANCH, I_DISP, I_ELEMENT, I_OMEGA, I_STATUS, I_STIFFNESS, I_TIME, NEWTON_FAILED, NONFINITE, NOT_CONVERGED, OK, OVERFLOW, S, U, UNRESOLVED, X_A, X_CUR, X_D, X_E_HYST, X_E_IN, X_E_VISC, X_ITER, X_LEVEL, X_LEVEL_USED, X_OMEGA_DT2, X_STEPS, X_SUBSTEPS, X_V)
from rbhyst.solve.kernels.elements import copy_rows, omega_squared, omega_squared_exact, substep_load


@njit(cache=True, error_model="numpy", _nrt=False)
def _fail(info, status, element, t):
    info[I_STATUS] = status
    info[I_ELEMENT] = element
    info[I_TIME] = t


@njit(cache=True, error_model="numpy", _nrt=False)
def run_chunk(method, coef, mass, minv, cm, damped, bvec, mult, params, wgt,
              load, t0, h_c, nsub_c, n_steps, omega_dt_limit, min_level, max_level, newton_tol, newton_max_iter,
              x, st, st_save, kpeak, out_d, out_v, out_u, out_f, out_e, info):
    """Advance the state x, st over n_steps output steps of nsub_c compute steps of h_c each.

    load: (n_steps * nsub_c + 1, 3) generalized load on the compute grid from the chunk's
    start time t0. Row k of out_* receives the state after output step k + 1. out_e columns:
    input energy, kinetic energy, hysteretic work, viscous work (cumulative).
    Every compute step is split into at least 2**min_level substeps (a structure-dependent
    method needs omega_0 h within the limit too, see simulate.min_level). A step whose Newton
    iterations fail is retried, like a stiff one, with twice the substeps.
    Rows hold no acceleration: the caller takes it from the equation of motion at the row's
    state and time (rbhyst.solve.history.Layout), never from a method's own variable (KR-alpha's
    is a(t) + O(h); any method's carries the load averaged over a step near a jump).
    Returns the number of rows written; info tells how it ended.
    """
    ne = bvec.shape[0]
    d0 = x[X_D]
    d1 = x[X_D + 1]
    d2 = x[X_D + 2]
    v0 = x[X_V]
    v1 = x[X_V + 1]
    v2 = x[X_V + 2]
    a0 = x[X_A]
    a1 = x[X_A + 1]
    a2 = x[X_A + 2]
    e_in = x[X_E_IN]
    e_hyst = x[X_E_HYST]
    e_visc = x[X_E_VISC]
    steps_taken = x[X_STEPS]
    iterations = x[X_ITER]
    substeps = x[X_SUBSTEPS]
    level_used = int(x[X_LEVEL_USED])
    omega_dt2_seen = x[X_OMEGA_DT2]
    level = int(x[X_LEVEL])
    cur = int(x[X_CUR])
    limit2 = omega_dt_limit * omega_dt_limit
    info[I_STATUS] = OK
    row = 0
    for j in range(n_steps * nsub_c):
        # the state to restart this compute step from if a substep is rejected
        sd0, sd1, sd2, sv0, sv1, sv2, sa0, sa1, sa2 = d0, d1, d2, v0, v1, v2, a0, a1, a2
        s_in, s_hyst, s_visc, s_cur = e_in, e_hyst, e_visc, cur
        saved = False
        level = max(level - 1, min_level)
        while True:
            nsub = 1 << level
            if nsub > 1 and not saved:
                copy_rows(st[cur], st_save)  # substeps overwrite both buffers: keep the start
                saved = True
            inv_nsub = 1.0 / nsub
            h = h_c * inv_nsub
            accepted = True
            for k in range(nsub):
                # load at the ends of the substep, linear within the compute step
                w0 = k * inv_nsub
                w1 = (k + 1) * inv_nsub
                ok, bad, work, its, n0, n1, n2, nv0, nv1, nv2, na0, na1, na2, _, _, _ = take_step(
                    method, coef, level, mass, minv, cm, damped, bvec, mult, params, st, cur,
                    d0, d1, d2, v0, v1, v2, a0, a1, a2, load, j, w0, w1, h, kpeak,
                    newton_tol, newton_max_iter)
                iterations += its
                steps_taken += 1
                t_now = t0 + (j + w1) * h_c
                if not ok:
                    if bad == NEWTON_FAILED and level < max_level:
                        accepted = False  # retry the compute step with twice the substeps
                        break
                    if bad == NEWTON_FAILED:
                        _fail(info, NOT_CONVERGED, -1, t_now)
                    else:
                        _fail(info, OVERFLOW if bad >= 0 else NONFINITE, bad, t_now)
                    return row
                # resolution check on the stiffest instantaneous mode of the step
                lam, worst = omega_squared(mult, kpeak, wgt)
                if lam * h * h > limit2:
                    lam = omega_squared_exact(bvec, mult, minv, kpeak)
                    if lam * h * h > limit2:
                        if level >= max_level:
                            _fail(info, UNRESOLVED, worst, t_now)
                            info[I_STIFFNESS] = kpeak[worst, 0]
                            info[I_OMEGA] = math.sqrt(lam)
                            info[I_DISP] = st[1 - cur, worst, U]  # the trial state that failed
                            info[I_BRANCH] = st[1 - cur, worst, S]
                            return row
                        accepted = False
                        break
                if lam * h * h > omega_dt2_seen:
                    omega_dt2_seen = lam * h * h
                pa0, pa1, pa2, pb0, pb1, pb2 = substep_load(load, j, w0, w1)
                e_in += 0.5 * ((pa0 + pb0) * (n0 - d0) + (pa1 + pb1) * (n1 - d1) + (pa2 + pb2) * (n2 - d2))
                e_hyst += work
                if damped:
                    # trapezoidal work of the viscous forces C v over the step
                    s0 = v0 + nv0
                    s1 = v1 + nv1
                    s2 = v2 + nv2
                    e_visc += 0.5 * ((cm[0, 0] * s0 + cm[0, 1] * s1 + cm[0, 2] * s2) * (n0 - d0)
                                     + (cm[1, 0] * s0 + cm[1, 1] * s1 + cm[1, 2] * s2) * (n1 - d1)
                                     + (cm[2, 0] * s0 + cm[2, 1] * s1 + cm[2, 2] * s2) * (n2 - d2))
                d0, d1, d2, v0, v1, v2, a0, a1, a2 = n0, n1, n2, nv0, nv1, nv2, na0, na1, na2
                cur = 1 - cur
            if accepted:
                if level > 0:
                    substeps += nsub
                    level_used = max(level_used, level)
                break
            # restart the compute step with twice as many substeps
            d0, d1, d2, v0, v1, v2, a0, a1, a2 = sd0, sd1, sd2, sv0, sv1, sv2, sa0, sa1, sa2
            e_in, e_hyst, e_visc = s_in, s_hyst, s_visc
            cur = s_cur
            if saved:
                copy_rows(st_save, st[cur])
            level += 1

        if not (math.isfinite(d0) and math.isfinite(d1) and math.isfinite(d2)
                and math.isfinite(a0) and math.isfinite(a1) and math.isfinite(a2)):
            _fail(info, NONFINITE, -1, t0 + (j + 1) * h_c)
            return row

        if (j + 1) % nsub_c == 0:
            out_d[row, 0] = d0
            out_d[row, 1] = d1
            out_d[row, 2] = d2
            out_v[row, 0] = v0
            out_v[row, 1] = v1
            out_v[row, 2] = v2
            for e in range(ne):
                out_u[row, e] = st[cur, e, U]
                out_f[row, e] = st[cur, e, F]
            out_e[row, E_IN] = e_in
            out_e[row, E_KIN] = 0.5 * (mass[0] * v0 * v0 + mass[1] * v1 * v1 + mass[2] * v2 * v2)
            out_e[row, E_HYST] = e_hyst
            out_e[row, E_VISC] = e_visc
            row += 1

    x[X_D] = d0
    x[X_D + 1] = d1
    x[X_D + 2] = d2
    x[X_V] = v0
    x[X_V + 1] = v1
    x[X_V + 2] = v2
    x[X_A] = a0
    x[X_A + 1] = a1
    x[X_A + 2] = a2
    x[X_E_IN] = e_in
    x[X_E_HYST] = e_hyst
    x[X_E_VISC] = e_visc
    x[X_STEPS] = steps_taken
    x[X_ITER] = iterations
    x[X_SUBSTEPS] = substeps
    x[X_LEVEL_USED] = level_used
    x[X_OMEGA_DT2] = omega_dt2_seen
    x[X_LEVEL] = level
    x[X_CUR] = cur
    return row
