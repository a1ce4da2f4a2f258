"""Element forces along a deformation history with every reversal located within its step.

The time-stepping loop starts an element's new branch at the step where its deformation
turned (seed eq. 14 with t_P at that node), not at the turn itself: the branch's origin is off
by O(h^2) and so is every force along the branch until its memory fades. The error estimate
(rbhyst.solve.companion) re-drives each element along its companion's deformation with the
turn put where it is, the vertex of the parabola through the three samples around it, so that
the companion's forces carry none of that error and the difference shows the run's. Where no
step was split into substeps the companion's own rows report these forces (kernels.loop,
LOCATED: the same updates, to rounding) and this pass is not needed; in a split step the
loop puts a turn between substeps, with a step before of another length, and this pass,
between the compute nodes, is the one measured against the adaptive solution (a 20 g shock:
0.96 of the true error against 0.23).
"""

from numba import njit

from rbhyst.model.stop import STOP_ROW, stop_update
from rbhyst.model.vrm import vrm_update
from rbhyst.solve.kernels.layout import A, DL, DU, F, FS, G, K, S, U


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _stop(params, e, u0, u1, ml, mu):
    """Element e's stop from u0 to u1 (rbhyst.model.stop): its force there and the peaks after."""
    if params.shape[1] <= STOP_ROW:
        return 0.0, ml, mu
    fs, ml, mu, _, _, _, _, _, _ = stop_update(params, e, u0, u1, ml, mu)
    return fs, ml, mu


@njit(cache=True, error_model="numpy", _nrt=False)
def _drive(params, e, uu, f, s, g, k, a, ml, mu, u, f_out, stop):
    """Element row e from its state (uu, f, s, g, k, a; its stop's peaks ml, mu) at sample 0 of u
    through samples 1 .. stop - 1, f_out[i, e] each one's force (its stop's with it); a sample with
    one after it in u (u's last is looked at only) has its turn's vertex inserted where it falls
    (the stop's peak there too). Returns (-1 or the sample at which the element left its
    calibrated range, the state reached)."""
    n = u.shape[0]
    for i in range(1, stop):
        # the vertex of sample i's parabola, if i turns and the vertex lies before it
        if i < n - 1:
            d0 = u[i, e] - u[i - 1, e]
            d1 = u[i + 1, e] - u[i, e]
            if d0 * d1 < 0.0:
                c = u[i - 1, e] - u[i + 1, e]
                x = 0.5 * c / (d1 - d0)  # its time after sample i, in steps (|x| <= 1/2)
                peak = u[i, e] - 0.25 * c * x
                if x < 0.0:
                    f, s, g, k, a, _, _, ok = vrm_update(params, e, uu, f, s, g, k, a, peak)
                    if not ok:
                        return i, uu, f, s, g, k, a, ml, mu
                    _, ml, mu = _stop(params, e, uu, peak, ml, mu)
                    uu = peak
        f, s, g, k, a, _, _, ok = vrm_update(params, e, uu, f, s, g, k, a, u[i, e])
        if not ok:
            return i, uu, f, s, g, k, a, ml, mu
        fs, ml, mu = _stop(params, e, uu, u[i, e], ml, mu)
        uu = u[i, e]
        f_out[i, e] = f + fs if fs != 0.0 else f
        if i < n - 1:
            d0 = u[i, e] - u[i - 1, e]
            d1 = u[i + 1, e] - u[i, e]
            if d0 * d1 < 0.0:
                c = u[i - 1, e] - u[i + 1, e]
                x = 0.5 * c / (d1 - d0)
                if x > 0.0:  # the vertex lies after sample i: drive to it now
                    peak = u[i, e] - 0.25 * c * x
                    f, s, g, k, a, _, _, ok = vrm_update(params, e, uu, f, s, g, k, a, peak)
                    if not ok:
                        return i, uu, f, s, g, k, a, ml, mu
                    _, ml, mu = _stop(params, e, uu, peak, ml, mu)
                    uu = peak
    return -1, uu, f, s, g, k, a, ml, mu


@njit(cache=True, error_model="numpy", _nrt=False)
def redrive(params, st0, u, f_out):
    """Drive element row e of ``params`` (ne, 2 or 3, 8: rbhyst.model.stop) from its state st0[e] (the
    VRM's six columns, or layout.N_STATE with its stop's) through the samples
    u[:, e] (equally spaced in time), a reversal's vertex inserted between the samples it falls
    between; f_out[i, e] the force at sample i (f_out[0] is st0's). Returns -1, or the sample at
    which an element left its calibrated range."""
    for e in range(u.shape[1]):
        stops = st0.shape[1] > FS  # (a state of the VRM's six columns alone: no stop)
        f_out[0, e] = st0[e, F] + st0[e, FS] if stops and st0[e, FS] != 0.0 else st0[e, F]
        ml = st0[e, DL] if stops else 0.0
        mu = st0[e, DU] if stops else 0.0
        bad, _, _, _, _, _, _, _, _ = _drive(params, e, st0[e, U], st0[e, F], st0[e, S], st0[e, G], st0[e, K],
                                             st0[e, A], ml, mu, u, f_out, u.shape[0])
        if bad >= 0:
            return bad
    return -1


@njit(cache=True, error_model="numpy", _nrt=False)
def redrive_on(params, state, u, f_out, last):
    """redrive a window at a time: every element from its ``state`` (ne, 6 or layout.N_STATE, at sample 0 of u,
    which is driven already) through samples 1 .. m - 2 of u (m, ne), the last one only looked
    at (it decides whether m - 2 turns), or through m - 1 where ``last`` (the history's end); the
    state reached written back. The next window starts at the last sample driven, the one after
    it next: the same forces, to the bit, as redrive of the whole history. Returns as redrive."""
    stop = u.shape[0] if last else u.shape[0] - 1
    for e in range(u.shape[1]):
        stops = state.shape[1] > DU
        bad, uu, f, s, g, k, a, ml, mu = _drive(params, e, state[e, U], state[e, F], state[e, S], state[e, G],
                                                state[e, K], state[e, A], state[e, DL] if stops else 0.0,
                                                state[e, DU] if stops else 0.0, u, f_out, stop)
        if bad >= 0:
            return bad
        state[e, U], state[e, F], state[e, S], state[e, G], state[e, K], state[e, A] = uu, f, s, g, k, a
        if stops:
            state[e, DL], state[e, DU] = ml, mu
    return -1
