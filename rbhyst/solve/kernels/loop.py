"""The time-stepping loop shared by every fixed-step method, one chunk of output steps at a time.

Each compute step is checked against the stiffest mode it has to resolve: the loop halves
the step (the load interpolated linearly) until ``omega_max * h <= omega_dt_limit`` or the
substep level runs out. The loop's running state (x: displacement, velocity, acceleration,
energies, counters; st: the element states) is carried from one call to the next, so that
a run of any length keeps only one chunk of rows in memory.

The body has n coordinates, the length of the tuples mass and minv: the loop and the steps work
on vectors of n in the work space the caller gives (layout.W_*), so the same source runs the
seed's plane body (n = 3) and any other, compiled for each n (a compile-time constant: see
rbhyst.solve.integrators.steps).
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.solve.integrators.steps import KR_ALPHA, NEWMARK, chang_step, kr_alpha_step, newmark_step
from rbhyst.solve.kernels.layout import (E_HYST, E_IN, E_KIN, E_VISC, FB, FS, I_BRANCH, I_DISP, I_ELEMENT, I_OMEGA, I_STATUS, I_STIFFNESS, I_TIME, LOCATED, NEWTON_FAILED, NONFINITE, NOT_CONVERGED, OK, OVERFLOW, S, SPATIAL, U, UNRESOLVED, W_A, W_AN, W_D, W_DN, W_PA, W_PB, W_Q, W_SA, W_SD, W_SV, W_V, W_VN, W_X, W_Z, X_CUR, X_E_HYST, X_E_IN, X_E_VISC, X_ITER, X_LEVEL, X_LEVEL_USED, X_OMEGA_DT2, X_Q, X_STEPS, X_SUBSTEPS)
from rbhyst.solve.kernels.elements import (copy_rows, copy_vector, element_force, omega_squared, omega_squared_exact,
                                           row_dot, turned_dampers)
from rbhyst.solve.kernels.rotations import compose


@njit(cache=True, error_model="numpy", _nrt=False)
def _fail(info, status, element, t):
    info[I_STATUS] = status
    info[I_ELEMENT] = element
    info[I_TIME] = t


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def element_force_with(f, st, c, e):
    """The VRM force f of element e with its stop's in st[c] (f itself where the stop bears nothing)."""
    fs = st[c, e, FS]
    return f + fs if fs != 0.0 else f


@njit(cache=True, error_model="numpy", _nrt=False)
def run_chunk(method, coef, mass, minv, cm, damped, bvec, axial, rot, mult, params, wgt,
              load, t0, h_c, nsub_c, n_steps, omega_dt_limit, min_level, max_level, newton_tol, newton_max_iter,
              x, st, st_save, kpeak, bq, w, wm, out_d, out_v, out_u, out_f, out_e, out_fb, levels, force, info):
    """Advance the state x, st over n_steps output steps of nsub_c compute steps of h_c each.

    mass, minv: the diagonals of M and M^-1 as tuples of n (n is their length). wgt (ne,): each
    row's b^T M^-1 b for the stiffness monitor (a body in space with exact rotations rewrites it
    at every step, its rows turning). axial, rot: the
    kinematics, bq (ne, n) work space for the rows b_e(q) (rbhyst.solve.kernels.elements.update_elements).
    load: (n_steps * nsub_c + 1, n) generalized load on the compute grid from the chunk's
    start time t0. Row k of out_* receives the state after output step k + 1. out_e columns:
    input energy, kinetic energy, hysteretic work (the elements' forces', their stops' with them), viscous
    work (cumulative).
    w (layout.N_W, n) and wm (n, n): work space.
    Every compute step is split into at least 2**min_level substeps (a structure-dependent
    method needs omega_0 h within the limit too, see simulate.min_level). A step whose Newton
    iterations fail is retried, like a stiff one, with twice the substeps.
    levels (n_steps * nsub_c,): each compute step's substep level as accepted (2**level
    substeps); with ``force`` each step takes the level it holds, the stiffness monitor's
    judgement aside (a companion run steps as its run stepped, within its error of the run's
    states: rbhyst.solve.companion; only Newton's failure still splits a step further).
    With rot = LOCATED (the companion) and a row at every compute step, a row whose element
    turned before it (the turn's vertex found by the next step) takes the force re-driven on the
    new branch (elements.located_update), and out_fb (ne,), the forces of the row before the
    chunk's first, alike (left as they are where they stand): the forces the companion reports,
    each turn where it falls.
    Rows hold no acceleration: the caller takes it from the equation of motion at the row's
    state and time (rbhyst.solve.history.Layout), never from a method's own variable (KR-alpha's
    is a(t) + O(h); any method's carries the load averaged over a step near a jump).
    Returns the number of rows written; info tells how it ended.

    One function, long, because numba keeps the loop's state in registers only within a function.
    """
    ne = bvec.shape[0]
    n = len(minv)  # a compile-time constant: mass and minv are tuples (see integrators.steps)
    d, v, a = w[W_D], w[W_V], w[W_A]
    dn, vn, an = w[W_DN], w[W_VN], w[W_AN]
    pa, pb, z = w[W_PA], w[W_PB], w[W_Z]
    for i in range(n):
        d[i] = x[X_Q + i]
        v[i] = x[X_Q + n + i]
        a[i] = x[X_Q + 2 * n + i]
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
        # the state to restart this compute step from if a substep is rejected: a rejected first
        # substep has changed nothing, so it is copied only where there are several
        s_in, s_hyst, s_visc, s_cur = e_in, e_hyst, e_visc, cur
        saved = False
        level = max(levels[j] if force else level - 1, min_level)
        while True:
            nsub = 1 << level
            if nsub > 1 and not saved:
                copy_rows(st[cur], st_save)  # substeps overwrite both buffers: keep the start
                copy_vector(d, w[W_SD], n)
                copy_vector(v, w[W_SV], n)
                copy_vector(a, w[W_SA], n)
                saved = True
            inv_nsub = 1.0 / nsub
            h = h_c * inv_nsub
            accepted = True
            for k in range(nsub):
                # load at the ends of the substep, linear within the compute step
                w0 = k * inv_nsub
                w1 = (k + 1) * inv_nsub
                if method == NEWMARK:
                    ok, bad, work, its = newmark_step(mass, cm, damped, bvec, axial, rot, mult, params, st, cur, w, wm,
                                                      load, j, w0, w1, h, kpeak, bq, newton_tol, newton_max_iter)
                elif method == KR_ALPHA:
                    ok, bad, work = kr_alpha_step(coef, level, mass, minv, cm, damped, bvec, axial, rot, mult, params,
                                                  st, cur, w, load, j, w0, w1, h, kpeak, bq)
                    its = 1
                else:  # Chang's method and central difference share their step (their coefficients differ)
                    ok, bad, work = chang_step(coef, level, mass, minv, cm, damped, bvec, axial, rot, mult, params, st,
                                               cur, w, load, j, w0, w1, h, kpeak, bq)
                    its = 1
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
                if rot == SPATIAL:  # the trace bound's weights b^T M^-1 b at the rows the step reached
                    for e in range(ne):
                        acc = 0.0
                        for i in range(n):
                            acc += bq[e, i] * bq[e, i] * minv[i]
                        wgt[e] = acc
                lam, worst = omega_squared(mult, kpeak, wgt)
                if lam * h * h > limit2 and not force:
                    lam = omega_squared_exact(bq if rot >= 0 or rot == SPATIAL else bvec, mult, minv, kpeak, wm, w[W_Q])
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
                # work of the load (the step left it in pa, pb), trapezoidal in displacement
                acc = (pa[0] + pb[0]) * (dn[0] - d[0])
                for i in range(1, n):
                    acc += (pa[i] + pb[i]) * (dn[i] - d[i])
                e_in += 0.5 * acc
                e_hyst += work
                if damped:
                    # trapezoidal work of the viscous forces C v over the step
                    for i in range(n):
                        z[i] = v[i] + vn[i]
                    acc = row_dot(cm, 0, z, n) * (dn[0] - d[0])
                    for i in range(1, n):
                        acc += row_dot(cm, i, z, n) * (dn[i] - d[i])
                    if cm.shape[0] > n:  # dampers whose rows turn, at the step's end
                        wx = w[W_X]
                        for i in range(n):
                            wx[i] = 0.0
                        turned_dampers(cm, rot, d, dn, z, 0, wx, 1.0, n)
                        for i in range(n):
                            acc += wx[i] * (dn[i] - d[i])
                    e_visc += 0.5 * acc
                if rot == SPATIAL:  # the step's turn, composed on the body's attitude
                    compose(d, dn)
                copy_vector(dn, d, n)
                copy_vector(vn, v, n)
                copy_vector(an, a, n)
                cur = 1 - cur
            if accepted:
                if level > 0:
                    substeps += nsub
                    level_used = max(level_used, level)
                levels[j] = level
                break
            # restart the compute step with twice as many substeps
            e_in, e_hyst, e_visc = s_in, s_hyst, s_visc
            cur = s_cur
            if saved:
                copy_vector(w[W_SD], d, n)
                copy_vector(w[W_SV], v, n)
                copy_vector(w[W_SA], a, n)
                copy_rows(st_save, st[cur])
            level += 1

        finite = True
        for i in range(n):
            finite = finite and math.isfinite(d[i]) and math.isfinite(a[i])
        if not finite:
            _fail(info, NONFINITE, -1, t0 + (j + 1) * h_c)
            return row

        if (j + 1) % nsub_c == 0:
            for i in range(n):
                out_d[row, i] = d[i]
                out_v[row, i] = v[i]
            for e in range(ne):
                out_u[row, e] = st[cur, e, U]
                out_f[row, e] = element_force(st, cur, e)
            if rot == LOCATED and nsub_c == 1 and level == 0:
                # (a step split into substeps located its turns between them, not at the rows)
                for e in range(ne):
                    back = st[cur, e, FB]
                    if not math.isnan(back):
                        back = element_force_with(back, st, 1 - cur, e)  # (the row before's stop)
                        if row > 0:
                            out_f[row - 1, e] = back
                        else:
                            out_fb[e] = back
            out_e[row, E_IN] = e_in
            kinetic = mass[0] * v[0] * v[0]
            for i in range(1, n):
                kinetic += mass[i] * v[i] * v[i]
            out_e[row, E_KIN] = 0.5 * kinetic
            out_e[row, E_HYST] = e_hyst
            out_e[row, E_VISC] = e_visc
            row += 1

    for i in range(n):
        x[X_Q + i] = d[i]
        x[X_Q + n + i] = v[i]
        x[X_Q + 2 * n + i] = a[i]
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
