"""Element rows at a new configuration (seed eqs. 5-17) and the stiffness bounds of the monitor.

Compiled with numba; called from the time-stepping loop and from each method's step.
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.model.stop import STOP_ROW, stop_update
from rbhyst.model.vrm import vrm_update
from rbhyst.solve.kernels.layout import A, DL, DU, F, FB, FS, G, IMP, K, LOCATED, NI, PD, PF, S, SPATIAL, U, UP
from rbhyst.solve.kernels.rotations import element_row, rotation, turned


@njit(cache=True, error_model="numpy", _nrt=False)
def sym3_max_eig(a11, a22, a33, a12, a13, a23):
    """Largest eigenvalue of a symmetric 3x3 matrix (trigonometric closed form)."""
    p1 = a12 * a12 + a13 * a13 + a23 * a23
    q = (a11 + a22 + a33) / 3.0
    if p1 <= 1e-30 * (a11 * a11 + a22 * a22 + a33 * a33):
        return max(a11, max(a22, a33))
    b11 = a11 - q
    b22 = a22 - q
    b33 = a33 - q
    p2 = b11 * b11 + b22 * b22 + b33 * b33 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    det = b11 * (b22 * b33 - a23 * a23) - a12 * (a12 * b33 - a23 * a13) + a13 * (a12 * a23 - b22 * a13)
    r = det / (2.0 * p * p * p)
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    return q + 2.0 * p * math.cos(phi)


@njit(cache=True, error_model="numpy", _nrt=False)
def sym_max_eig(a, n):
    """Largest eigenvalue of the symmetric (n, n) matrix a (overwritten where n > 3).

    Closed forms up to n = 3 (the plane body's is sym3_max_eig); beyond, cyclic Jacobi
    rotations to round-off (a few sweeps for n <= 6), which need no work space.
    """
    if n == 1:
        return a[0, 0]
    if n == 2:
        h = 0.5 * (a[0, 0] - a[1, 1])
        return 0.5 * (a[0, 0] + a[1, 1]) + math.sqrt(h * h + a[0, 1] * a[0, 1])
    if n == 3:
        return sym3_max_eig(a[0, 0], a[1, 1], a[2, 2], a[0, 1], a[0, 2], a[1, 2])
    for _ in range(100):
        off = 0.0
        diag = 0.0
        for i in range(n):
            diag += a[i, i] * a[i, i]
            for j in range(i + 1, n):
                off += a[i, j] * a[i, j]
        if off <= 1e-32 * diag or off == 0.0:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                # the rotation that zeroes a[p, q] (Golub and Van Loan, Algorithm 8.5.1)
                tau = (a[q, q] - a[p, p]) / (2.0 * apq)
                t = (1.0 if tau >= 0.0 else -1.0) / (abs(tau) + math.sqrt(1.0 + tau * tau))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = t * c
                for k in range(n):
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(n):
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
    top = a[0, 0]
    for i in range(1, n):
        top = max(top, a[i, i])
    return top


@njit(cache=True, error_model="numpy", _nrt=False)
def update_spatial(bvec, axial, mult, params, q0, q, st, cur, kpeak, r, bq):
    """update_elements for a body in space with exact kinematics (rot = SPATIAL): the rows at the
    attitude R(q0[3:6]) exp(q[3:6] - q0[3:6]) (rotations.element_row). Returns (ok, bad, work)."""
    n = len(r)
    for i in range(n):
        r[i] = 0.0
    work = 0.0
    rm = turned(q0, q)
    nxt = 1 - cur
    for e in range(bvec.shape[0]):
        u = element_row(bvec, axial, e, rm, q, bq)
        f, s, g, k, a, kstart, w, ok = vrm_update(params, e, st[cur, e, U], st[cur, e, F], st[cur, e, S],
                                                  st[cur, e, G], st[cur, e, K], st[cur, e, A], u)
        if not ok:
            return False, e, work
        st[nxt, e, U] = u
        st[nxt, e, F] = f
        st[nxt, e, S] = s
        st[nxt, e, G] = g
        st[nxt, e, K] = k
        st[nxt, e, A] = a
        kpeak[e, 0] = max(kstart, k)
        kpeak[e, 1] = k
        if params.shape[1] > STOP_ROW:
            f, w = stop_step(params, e, st, cur, u, f, w, kpeak)
        work += mult[e] * w
        mf = mult[e] * f
        for i in range(n):
            r[i] += mf * bq[e, i]
    return True, -1, work


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def stop_step(params, e, st, cur, u, f, w, kpeak):
    """Element e's stop (rbhyst.model.stop) over its step from st[cur, e, U] to u, after its VRM's:
    its state into st[1 - cur], its tangents added to kpeak[e]. Returns the element's force and
    work with the stop's (as they were, to the bit, where the stop took no part)."""
    nxt = 1 - cur
    fs, ml, mu, k_top, k_end, ws, loss, began, engaged = stop_update(params, e, st[cur, e, U], u, st[cur, e, DL],
                                                                    st[cur, e, DU])
    st[nxt, e, DL] = ml
    st[nxt, e, DU] = mu
    st[nxt, e, FS] = fs
    st[nxt, e, IMP] = st[cur, e, IMP] + loss
    st[nxt, e, NI] = st[cur, e, NI] + (1.0 if began else 0.0)
    st[nxt, e, PF] = max(st[cur, e, PF], abs(fs))
    st[nxt, e, PD] = max(st[cur, e, PD], max(mu, ml))
    if not engaged:
        return f, w
    kpeak[e, 0] += k_top
    kpeak[e, 1] += k_end
    return f + fs, w + ws


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def element_force(st, cur, e):
    """Element e's force in st[cur]: its VRM's and its stop's (F alone where the stop bears nothing)."""
    fs = st[cur, e, FS]
    return st[cur, e, F] + fs if fs != 0.0 else st[cur, e, F]


@njit(cache=True, error_model="numpy", _nrt=False)
def start_spatial(bvec, axial, mult, st, cur, q, r, bq):
    """start_rows for a body in space with exact kinematics."""
    n = len(r)
    for i in range(n):
        r[i] = 0.0
    rm = rotation(q[3], q[4], q[5])
    for e in range(bvec.shape[0]):
        mf = mult[e] * element_force(st, cur, e)
        element_row(bvec, axial, e, rm, q, bq)
        for i in range(n):
            r[i] += mf * bq[e, i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def update_elements(bvec, axial, rot, mult, params, q0, q, st, cur, kpeak, r, bq, n):
    """Elements at the new configuration q (n,) (eqs. 5-11): u_e = b_e . q, R = sum mult b f.

    st: (2, ne, layout.N_STATE) element states; st[cur] holds the state at the start of the step
    (columns U, F, S, G, K, A, see hysteresis.vrm_update; where params has a third row, each
    element's stop, rbhyst.model.stop: its columns DL .. PD, its force added to the element's
    and its tangents to kpeak, stop_step), st[1 - cur] receives the new
    state (two buffers used in turn: an accepted step copies nothing); kpeak (ne, 2) receives
    the largest tangent over the step and the tangent at its end; r (n,) the restoring force.
    n = bvec.shape[1], given by the caller: inlined into a kernel where it is a compile-time
    constant (rbhyst.solve.kernels.loop), every loop over the coordinates unrolls.
    rot >= 0: exact kinematics about the coordinate q[rot] (rbhyst.model.kinematics):
    u_e = sum_i b_i q_i (i != rot) + b_rot sin(theta) + axial_e (cos(theta) - 1), its row
    b_e(q) = du_e/dq into bq (ne, n), and the geometric stiffness sum mult f d2u_e/dtheta2
    returned; rot = SPATIAL: a body in space with exact kinematics, the step from q0 to q
    turning it by q[3:6] - q0[3:6] in its own axes (rbhyst.solve.kernels.rotations), u_e =
    d . (u + R x - x) and b_e(q) = (d, x x R^T d) in bq (rotations.element_row), no geometric
    stiffness returned (Newmark's Newton matrix goes without it in space: its iterations
    converge to the same tolerance); rot = SMALL: the seed's rows, bq untouched.
    Returns (ok, bad element, work of all element forces over the step, geometric stiffness).
    Long, because it is inlined into every method's step: one loop over the elements, whose
    state numba keeps in registers only within a function.
    """
    if rot == SPATIAL:  # one call, compiled once: the plane's kernels carry none of it inlined
        ok, bad, work = update_spatial(bvec, axial, mult, params, q0, q, st, cur, kpeak, r, bq)
        return ok, bad, work, 0.0
    for i in range(n):
        r[i] = 0.0
    work = 0.0
    kgeo = 0.0
    sn = 0.0
    cs = 1.0
    cm1 = 0.0
    if rot >= 0:
        sn = math.sin(q[rot])
        cs = math.cos(q[rot])
        half = math.sin(0.5 * q[rot])
        cm1 = -2.0 * half * half  # cos - 1 without cancellation
    for e in range(bvec.shape[0]):
        if rot >= 0:
            u = 0.0
            for i in range(n):
                if i != rot:
                    u += bvec[e, i] * q[i]
                    bq[e, i] = bvec[e, i]
            u += bvec[e, rot] * sn + axial[e] * cm1
            bq[e, rot] = bvec[e, rot] * cs - axial[e] * sn
        else:
            u = bvec[e, 0] * q[0]
            for i in range(1, n):
                u += bvec[e, i] * q[i]
        back = math.nan
        if rot == LOCATED and _turns(st, cur, e, u):
            # (a call only where it turns: along a branch the inlined update below; a call at
            # every step cost the companion a quarter of its time)
            f, s, g, k, a, kstart, w, ok, back = located_update(params, e, st, cur, u)
        else:
            f, s, g, k, a, kstart, w, ok = vrm_update(params, e, st[cur, e, U], st[cur, e, F], st[cur, e, S],
                                                      st[cur, e, G], st[cur, e, K], st[cur, e, A], u)
        if not ok:
            return False, e, work, kgeo
        nxt = 1 - cur
        st[nxt, e, UP] = st[cur, e, U]
        st[nxt, e, U] = u
        st[nxt, e, F] = f
        st[nxt, e, S] = s
        st[nxt, e, G] = g
        st[nxt, e, K] = k
        st[nxt, e, A] = a
        st[nxt, e, FB] = back
        kpeak[e, 0] = max(kstart, k)
        kpeak[e, 1] = k
        if params.shape[1] > STOP_ROW:
            f, w = stop_step(params, e, st, cur, u, f, w, kpeak)
        m = mult[e]
        work += m * w
        mf = m * f
        if rot >= 0:
            for i in range(n):
                r[i] += mf * bq[e, i]
            kgeo -= mf * (bvec[e, rot] * sn + axial[e] * cs)
        else:
            for i in range(n):
                r[i] += mf * bvec[e, i]
    return True, -1, work, kgeo


@njit(cache=True, error_model="numpy", _nrt=False)
def static_update(bvec, axial, rot, mult, params, q, st, cur, kpeak, r, bq, out):
    """update_elements at q, from q (a step of the static path under gravity, rbhyst.solve.static),
    as a kernel of its own: built at install with the others, so that a run under gravity loads
    no numba. out (3,): ok (1 or 0), the bad element, the geometric stiffness."""
    ok, bad, _, kgeo = update_elements(bvec, axial, rot, mult, params, q, q, st, cur, kpeak, r, bq, bvec.shape[1])
    out[0] = 1.0 if ok else 0.0
    out[1] = bad
    out[2] = kgeo


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _turns(st, cur, e, u):
    """Whether element e, which moved along its branch the step before, turns on its way to u
    (located_update's test)."""
    u0 = st[cur, e, U]
    s0 = st[cur, e, S]
    return s0 != 0.0 and (u0 - st[cur, e, UP]) * s0 > 0.0 and (u - u0) * s0 < 0.0


@njit(cache=True, error_model="numpy", _nrt=False)
def located_update(params, e, st, cur, u):
    """vrm_update of element e from st[cur, e] to u where its last step moved along its branch and
    this one turns: to the turn first, the vertex of the parabola through the deformations a
    step before, now and at u (O(h^3) from the true turn where the node is O(h^2)), then on the
    new branch to u. Returns as vrm_update (the work of both parts; the tangent at the start of
    the new branch), and where the vertex lies before the node the step started from, that
    node's force on the new branch (the turn put before it: what the node's row reports), else
    NaN (its row's force stands, the turn after it)."""
    u0 = st[cur, e, U]
    s0 = st[cur, e, S]
    d0 = u0 - st[cur, e, UP]
    d1 = u - u0
    c = st[cur, e, UP] - u
    x = 0.5 * c / (d1 - d0)  # the vertex's time after the node, in steps (|x| <= 1/2)
    peak = u0 - 0.25 * c * x
    f, s, g, k, a, _, w, ok = vrm_update(params, e, u0, st[cur, e, F], s0, st[cur, e, G], st[cur, e, K],
                                         st[cur, e, A], peak)
    if not ok:
        return f, s, g, k, a, k, w, ok, math.nan
    back = math.nan
    if x < 0.0:
        back, _, _, _, _, _, _, fine = vrm_update(params, e, peak, f, s, g, k, a, u0)
        if not fine:
            back = math.nan
    f, s, g, k, a, kstart, w2, ok = vrm_update(params, e, peak, f, s, g, k, a, u)
    return f, s, g, k, a, kstart, w + w2, ok, back


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def start_rows(bvec, axial, rot, mult, st, cur, q, r, bq, n):
    """r (n,) = R at the start of a step, sum mult f b_e(q) from the forces in st[cur] (the
    rows at q where the kinematics are exact, rot != SMALL; bq: work space there)."""
    if rot == SPATIAL:
        start_spatial(bvec, axial, mult, st, cur, q, r, bq)
        return
    for i in range(n):
        r[i] = 0.0
    sn = 0.0
    cs = 1.0
    if rot >= 0:
        sn = math.sin(q[rot])
        cs = math.cos(q[rot])
    for e in range(bvec.shape[0]):
        mf = mult[e] * element_force(st, cur, e)
        for i in range(n):
            if i == rot:
                r[i] += mf * (bvec[e, i] * cs - axial[e] * sn)
            else:
                r[i] += mf * bvec[e, i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def omega_squared(mult, kpeak, wgt):
    """Trace bound on omega_max^2 = max eig(M^-1 K), K = sum mult k b b^T (k = kpeak[:, 0] >= 0).

    wgt[e] = b_e^T M^-1 b_e. Returns the bound and the element with the largest share of
    it; the exact eigenvalue (omega_squared_exact) is computed only when the bound is too high.
    """
    trace = 0.0
    worst = 0
    share = -1.0
    for e in range(mult.shape[0]):
        c = mult[e] * max(kpeak[e, 0], 0.0) * wgt[e]
        trace += c
        if c > share:
            share = c
            worst = e
    return trace, worst


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def bbt_sums(bvec, mult, k, col, minv, normalized, out, scale):
    """out (n, n) = K = sum mult k_e b_e b_e^T with k_e = k[e, col] (k: (ne, m)), or where
    ``normalized`` M^-1/2 K M^-1/2 with negative k_e taken as 0 (for omega_max^2); scale (n,)
    is work space; n = len(minv).

    Up to three coordinates the six sums are kept in registers and stored once (Newton's
    matrix is built at every iteration: summing into memory cost Newmark's step 8 %); n is
    a compile-time constant where this is inlined into a kernel, so only one branch is compiled.
    """
    n = len(minv)
    if n <= 3:
        s11 = s22 = s33 = s12 = s13 = s23 = 0.0
        q0 = math.sqrt(minv[0]) if normalized else 1.0
        q1 = math.sqrt(minv[1 % n]) if normalized else 1.0
        q2 = math.sqrt(minv[2 % n]) if normalized else 1.0
        for e in range(bvec.shape[0]):
            ke = mult[e] * (max(k[e, col], 0.0) if normalized else k[e, col])
            if ke == 0.0:
                continue
            x = bvec[e, 0] * q0
            y = bvec[e, 1] * q1 if n > 1 else 0.0
            z = bvec[e, 2] * q2 if n > 2 else 0.0
            s11 += ke * x * x
            s22 += ke * y * y
            s33 += ke * z * z
            s12 += ke * x * y
            s13 += ke * x * z
            s23 += ke * y * z
        out[0, 0] = s11
        if n > 1:
            out[1, 1] = s22
            out[0, 1] = s12
            out[1, 0] = s12
        if n > 2:
            out[2, 2] = s33
            out[0, 2] = s13
            out[2, 0] = s13
            out[1, 2] = s23
            out[2, 1] = s23
        return
    for i in range(n):
        scale[i] = math.sqrt(minv[i]) if normalized else 1.0
        for j in range(n):
            out[i, j] = 0.0
    for e in range(bvec.shape[0]):
        ke = mult[e] * (max(k[e, col], 0.0) if normalized else k[e, col])
        if ke == 0.0:
            continue
        for i in range(n):
            x = bvec[e, i] * scale[i]
            for j in range(i, n):
                out[i, j] += ke * x * (bvec[e, j] * scale[j])
    for i in range(n):
        for j in range(i):
            out[i, j] = out[j, i]


@njit(cache=True, error_model="numpy", _nrt=False)
def omega_squared_exact(bvec, mult, minv, kpeak, work, scale):
    """max eig(M^-1/2 K M^-1/2), the exact omega_max^2 of the tangent system (kpeak: (ne, 2),
    column 0); work (n, n) and scale (n,) are work space."""
    bbt_sums(bvec, mult, kpeak, 0, minv, True, work, scale)
    return sym_max_eig(work, len(minv))


@njit(cache=True, error_model="numpy", _nrt=False)
def copy_rows(src, dst):
    """dst[:] = src for (n, m) arrays, without a temporary."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def copy_vector(src, dst, n):
    """dst[:] = src for (n,) arrays, without a temporary."""
    for i in range(n):
        dst[i] = src[i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def mat_row(c, lv, k, i, x, n):
    """Row i of the coefficient matrix c[lv, k] times x (n,), summed from the first term."""
    acc = c[lv, k, i, 0] * x[0]
    for j in range(1, n):
        acc += c[lv, k, i, j] * x[j]
    return acc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def row_dot(m, i, x, n):
    """Row i of the matrix m (n, n) times x (n,), summed from the first term."""
    acc = m[i, 0] * x[0]
    for j in range(1, n):
        acc += m[i, j] * x[j]
    return acc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def substep_load(load, j, w0, w1, pa, pb, n):
    """The load at the fractions w0 (into pa) and w1 (into pb) of compute step j, linear within it."""
    for c in range(n):
        pa[c] = load[j, c] + w0 * (load[j + 1, c] - load[j, c])
        pb[c] = load[j, c] + w1 * (load[j + 1, c] - load[j, c])


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def arm_moment(load, j, w, n, theta):
    """Where forces act away from G with exact kinematics (load columns n, n + 1: r x p and
    r . p, rbhyst.model.system.Excitation.follow): what their turned arm adds to the moment at
    the fraction w of compute step j, (cos(theta) - 1) (r x p) - sin(theta) (r . p), and its
    derivative in theta."""
    x = load[j, n] + w * (load[j + 1, n] - load[j, n])
    dd = load[j, n + 1] + w * (load[j + 1, n + 1] - load[j, n + 1])
    half = math.sin(0.5 * theta)
    sn = math.sin(theta)
    return -2.0 * half * half * x - sn * dd, -sn * x - math.cos(theta) * dd


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def solve_in_place(a, b, n):
    """b := a^-1 b for the symmetric a (n, n) (overwritten), whose leading minors are positive
    (the matrices of a step: M / h^2 dominates). Up to n = 3 by cofactors, in registers (n is a
    compile-time constant where this is inlined into a kernel, and the branches not taken
    vanish); beyond, Gaussian elimination without pivoting. A singular matrix gives Inf or
    NaN, which the caller takes for one."""
    if n == 1:
        b[0] = b[0] / a[0, 0]
        return
    if n == 2:
        k11, k22, k12 = a[0, 0], a[1, 1], a[0, 1]
        det = k11 * k22 - k12 * k12
        g0, g1 = b[0], b[1]
        b[0] = (k22 * g0 - k12 * g1) / det
        b[1] = (k11 * g1 - k12 * g0) / det
        return
    if n == 3:
        k11, k22, k33, k12, k13, k23 = a[0, 0], a[1, 1], a[2, 2], a[0, 1], a[0, 2], a[1, 2]
        c11 = k22 * k33 - k23 * k23
        c12 = k13 * k23 - k12 * k33
        c13 = k12 * k23 - k13 * k22
        c22 = k11 * k33 - k13 * k13
        c23 = k12 * k13 - k11 * k23
        c33 = k11 * k22 - k12 * k12
        det = k11 * c11 + k12 * c12 + k13 * c13
        g0, g1, g2 = b[0], b[1], b[2]
        b[0] = (c11 * g0 + c12 * g1 + c13 * g2) / det
        b[1] = (c12 * g0 + c22 * g1 + c23 * g2) / det
        b[2] = (c13 * g0 + c23 * g1 + c33 * g2) / det
        return
    for k in range(n):
        piv = a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] / piv
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
            b[i] -= f * b[k]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= a[i, j] * b[j]
        b[i] = acc / a[i, i]


@njit(cache=True, error_model="numpy", _nrt=False)
def turned_dampers(cm, rot, q0, q, v, voff, out, sign, n):
    """out[i] += sign sum_d c_d (b_d(q) (b_d(q) . v) - b_d0 (b_d0 . v)): the viscous dampers' force
    beyond C0 v (cm's first n rows, the dampers at rest and Rayleigh's), where their rows turn
    with the body (exact kinematics; v = v[voff:voff + n]). Each damper is two more rows of cm
    (rbhyst.model.system.System.kernel_damping): in the plane (b1, b2, b3) and (c, c count, 0),
    its row b_d(q) = (b1, b2, b3 cos(theta) - c sin(theta)); in space (d, x') and (d', c count,
    0, 0), b_d(q) = (d, x' x R^T d') at the attitude R(q0) exp(q - q0) (rbhyst.model.rotations)."""
    nd = (cm.shape[0] - n) // 2
    if nd <= 0:
        return
    sn = 0.0
    cs = 1.0
    rm = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    if rot == SPATIAL:
        rm = turned(q0, q)
    elif rot >= 0:
        sn = math.sin(q[rot])
        cs = math.cos(q[rot])
    for k in range(nd):
        ra = n + 2 * k
        rb = ra + 1
        if rot == SPATIAL:
            d0, d1, d2 = cm[ra, 0], cm[ra, 1], cm[ra, 2]
            x0, x1, x2 = cm[ra, 3], cm[ra, 4], cm[ra, 5]
            c0, c1, c2 = cm[rb, 0], cm[rb, 1], cm[rb, 2]
            ct = cm[rb, 3]
            a0 = rm[0] * c0 + rm[3] * c1 + rm[6] * c2
            a1 = rm[1] * c0 + rm[4] * c1 + rm[7] * c2
            a2 = rm[2] * c0 + rm[5] * c1 + rm[8] * c2
            b3, b4, b5 = x1 * a2 - x2 * a1, x2 * a0 - x0 * a2, x0 * a1 - x1 * a0
            r3, r4, r5 = x1 * c2 - x2 * c1, x2 * c0 - x0 * c2, x0 * c1 - x1 * c0  # at rest
            tr = d0 * v[voff] + d1 * v[voff + 1] + d2 * v[voff + 2]
            s = tr + b3 * v[voff + 3] + b4 * v[voff + 4] + b5 * v[voff + 5]
            s0 = tr + r3 * v[voff + 3] + r4 * v[voff + 4] + r5 * v[voff + 5]
            f = sign * ct
            out[0] += f * d0 * (s - s0)
            out[1] += f * d1 * (s - s0)
            out[2] += f * d2 * (s - s0)
            out[3] += f * (b3 * s - r3 * s0)
            out[4] += f * (b4 * s - r4 * s0)
            out[5] += f * (b5 * s - r5 * s0)
        elif rot >= 0:
            ct = cm[rb, 1]
            s0 = 0.0
            for i in range(n):
                s0 += cm[ra, i] * v[voff + i]
            brot = cm[ra, rot] * cs - cm[rb, 0] * sn
            s = s0 + (brot - cm[ra, rot]) * v[voff + rot]
            for i in range(n):
                bi = brot if i == rot else cm[ra, i]
                out[i] += sign * ct * (bi * s - cm[ra, i] * s0)
