"""The compiled step of every fixed-step method.

Every step has the same inputs and outputs: a new method adds its module (its coefficients,
numpy only), its step here, and one branch where the loop (rbhyst.solve.kernels.loop) chooses
the step. The schemes are written out in each method's module docstring.

The explicit steps are inlined into the loop (a call per step made Chang's run of the seed
deck three times slower); Newmark's is called (see newmark_step). The choice is the loop's own
branch, not a function of its own inlined into it: numba inlines by copying the callee's whole
IR once per site, and that function, the three steps inlined in it, was two fifths of the
loop's compiling. A step takes at most 30 arguments (they take 21): past that, Python passes
them to it as one tuple, and numba cannot inline such a function.

A step works on vectors of the n coordinates, n = len(minv) (len(mass)): the state (d, v, a)
it starts from and the one it reaches are rows of the work space ``w``
(rbhyst.solve.kernels.layout, W_*), which the caller allocates (compiled code here allocates
nothing). The loop passes M and M^-1 as tuples, so that n is a compile-time constant and every
loop over the coordinates unrolls (with n a run-time value, the seed deck's stepping took
half as long again). Every constant matrix
of a step comes inverted from Python per substep level (``coef``, each method's
``coefficients``), so explicit steps only multiply; Newmark's Newton matrix changes with the
tangent and is solved in place. Sums run from the first term, in the order of q.

A body in space with exact kinematics (rot = SPATIAL, rbhyst.model.rotations) steps in its own
axes: v[3:6] is its angular velocity and a[3:6] its derivative in the body's principal axes,
d[3:6] its rotation vector; each method's displacement update gives the turn of the step,
which the loop composes on the right when the step is accepted (rbhyst.solve.kernels.rotations);
the moments of the load are turned into the body's axes at both ends of the step, and Euler's
gyroscopic term omega x J omega joins the restoring force, taken at the velocity the step
predicts for its end (v + h a: an O(h^2) error in a step's acceleration, an O(h^3) one in its
velocity, so every method keeps its order).
"""

import math

from numba import njit

from rbhyst.solve.kernels.layout import (NEWTON_FAILED, W_A, W_AN, W_D, W_DN, W_PA, W_PB, W_Q, W_R, W_RN, W_V, W_VN, W_X,
                                         W_Y, W_Z)
from rbhyst.solve.kernels.elements import (arm_moment, bbt_sums, mat_row, row_dot, solve_in_place, start_rows,
                                           substep_load, turned_dampers, update_elements)
from rbhyst.solve.kernels.layout import SPATIAL
from rbhyst.solve.kernels.rotations import add_geometric, body_load, gyroscopic, rotation, turned
from rbhyst.solve.integrators import central_difference, chang, kr_alpha, newmark
from rbhyst.solve.integrators.chang import B1, B2, MC_INV
from rbhyst.solve.integrators.kr_alpha import A_A, A_V, D_A, V_A, V_ANEW, X_NEW, X_OLD
from rbhyst.solve.integrators.newmark import ROUNDOFF2

CHANG = chang.KERNEL_ID
CENTRAL_DIFFERENCE = central_difference.KERNEL_ID
NEWMARK = newmark.KERNEL_ID
KR_ALPHA = kr_alpha.KERNEL_ID


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def chang_step(coef, lv, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, cur, w, load, j, w0, w1, h, kpeak,
               bq):
    """One step of Chang's method (coef = B1, B2, (M + h/2 C)^-1) or of central difference
    (B1 = I, B2 = I/2), from the element state st[cur] into st[1 - cur] and from w[W_D, W_V,
    W_A] into w[W_DN, W_VN, W_AN] (R(d+) in w[W_R], the load in w[W_PA], w[W_PB]).

    Returns (ok, bad element, element work).
    """
    n = len(minv)
    d, v, a = w[W_D], w[W_V], w[W_A]
    dn, vn, an = w[W_DN], w[W_VN], w[W_AN]
    pb, r, x = w[W_PB], w[W_R], w[W_X]
    substep_load(load, j, w0, w1, w[W_PA], pb, n)
    hh = h * h
    for i in range(n):
        dn[i] = d[i] + h * mat_row(coef, lv, B1, i, v, n) + hh * mat_row(coef, lv, B2, i, a, n)
    if rot >= 0 and load.shape[1] > n:  # forces whose arm turns with the body
        w[W_PA, rot] += arm_moment(load, j, w0, n, d[rot])[0]
        pb[rot] += arm_moment(load, j, w1, n, dn[rot])[0]
    elif rot == SPATIAL:  # the moments in the body's axes at both ends
        body_load(rotation(d[3], d[4], d[5]), load, j, w0, n, axial, w[W_PA])
        body_load(turned(d, dn), load, j, w1, n, axial, pb)
    ok, bad, work, kgeo = update_elements(bvec, axial, rot, mult, params, d, dn, st, cur, kpeak, r, bq, n)
    if not ok:
        return False, bad, 0.0
    for i in range(n):
        x[i] = pb[i] - r[i]
    if rot == SPATIAL:
        y = w[W_Y]
        for i in range(n):
            y[i] = v[i] + h * a[i]
        for i in range(3, 6):
            x[i] -= gyroscopic(mass, y, i)
    if damped:
        y = w[W_Y]
        for i in range(n):
            y[i] = v[i] + 0.5 * h * a[i]
        for i in range(n):
            x[i] -= row_dot(cm, i, y, n)
        if cm.shape[0] > n:  # dampers whose rows turn: their force beyond C0 v at the predicted end
            z = w[W_Z]
            for i in range(n):
                z[i] = v[i] + h * a[i]
            turned_dampers(cm, rot, d, dn, z, 0, x, -1.0, n)
        for i in range(n):
            an[i] = mat_row(coef, lv, MC_INV, i, x, n)
    else:
        for i in range(n):
            an[i] = minv[i] * x[i]
    for i in range(n):
        vn[i] = v[i] + 0.5 * h * (a[i] + an[i])
    return True, -1, work


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def kr_alpha_step(coef, lv, mass, minv, cm, damped, bvec, axial, rot, mult, params, st, cur, w, load, j, w0, w1, h,
                  kpeak, bq):
    """One step of the KR-alpha method (Kolay and Ricles 2014), v being the velocity at t:

        d+ = d + h v + h^2 (A2 - gamma I) a
        a+ = Mh^-1 [(1 - af)(p+ - R+) + af (p - R) - C v] - (coef A_A) a
        v+ = v + h (A1 - gamma I) a + h gamma a+

    (see ``coefficients``). ``a`` is the method's own acceleration variable; R at the
    start of the step comes from the element forces in st[cur].
    Returns (ok, bad element, element work); the state reached in w as chang_step's.
    """
    n = len(minv)
    d, v, a = w[W_D], w[W_V], w[W_A]
    dn, vn, an = w[W_DN], w[W_VN], w[W_AN]
    pa, pb, r, rn, x, y = w[W_PA], w[W_PB], w[W_R], w[W_RN], w[W_X], w[W_Y]
    start_rows(bvec, axial, rot, mult, st, cur, d, rn, bq, n)
    substep_load(load, j, w0, w1, pa, pb, n)
    hh = h * h
    for i in range(n):
        dn[i] = d[i] + h * v[i] + hh * mat_row(coef, lv, D_A, i, a, n)
    if rot >= 0 and load.shape[1] > n:  # forces whose arm turns with the body
        pa[rot] += arm_moment(load, j, w0, n, d[rot])[0]
        pb[rot] += arm_moment(load, j, w1, n, dn[rot])[0]
    elif rot == SPATIAL:  # the moments in the body's axes at both ends
        body_load(rotation(d[3], d[4], d[5]), load, j, w0, n, axial, pa)
        body_load(turned(d, dn), load, j, w1, n, axial, pb)
    ok, bad, work, kgeo = update_elements(bvec, axial, rot, mult, params, d, dn, st, cur, kpeak, r, bq, n)
    if not ok:
        return False, bad, 0.0
    for i in range(n):
        x[i] = pb[i] - r[i]
        y[i] = pa[i] - rn[i]
    if rot == SPATIAL:  # Euler's term at the start and at the end the step predicts (vn: work space)
        for i in range(n):
            vn[i] = v[i] + h * a[i]
        for i in range(3, 6):
            x[i] -= gyroscopic(mass, vn, i)
            y[i] -= gyroscopic(mass, v, i)
    if damped and cm.shape[0] > n:
        # dampers whose rows turn: their force beyond C0 v, weighted between the step's ends as the
        # restoring force is (the scheme's C v acts at the velocity at t + (1 - af) h)
        z = w[W_Z]
        for i in range(n):
            z[i] = v[i] + h * a[i]
        turned_dampers(cm, rot, d, dn, z, 0, x, -1.0, n)
        turned_dampers(cm, rot, d, d, v, 0, y, -1.0, n)
    for i in range(n):
        an[i] = mat_row(coef, lv, X_NEW, i, x, n) + mat_row(coef, lv, X_OLD, i, y, n) - mat_row(coef, lv, A_A, i, a, n)
    if damped:
        for i in range(n):
            an[i] -= mat_row(coef, lv, A_V, i, v, n)
    for i in range(n):
        vn[i] = v[i] + h * (mat_row(coef, lv, V_A, i, a, n) + mat_row(coef, lv, V_ANEW, i, an, n))
    return True, -1, work


# Not inlined, unlike the explicit steps: inlined, its Newton loop (the elements' update and the
# tangent's assembly inlined in it) was copied into the loop at every compiling, some 30 s of a
# body's first run on a cold cache; called, the seed deck's Newmark run takes some 9 % longer
# (15.6-16.3 -> 17.4-17.6 ms), its iterations being most of a step.
@njit(cache=True, error_model="numpy", _nrt=False)
def newmark_step(mass, cm, damped, bvec, axial, rot, mult, params, st, cur, w, wm, load, j, w0, w1, h, kpeak, bq, tol,
                 max_iter):
    """One Newmark step solved for d+ by Newton iterations from d + h v + h^2/2 a.

    The Jacobian is 4/h^2 M + 2/h C + K_t(d+), K_t = sum mult k_t b b^T with each
    element's closed-form tangent (seed eq. 16) at the trial point on the branch from its
    start state, assembled in wm (n, n) and solved in place (Gaussian elimination: it is
    symmetric, and 4/h^2 M keeps its pivots positive). Converged when the Newton
    correction is at most tol times the step's increment (both in the norm sqrt(x^T M x)),
    or below the round-off of d+ itself; the accepted iterate is the last one evaluated,
    so st[1 - cur], R and the work belong to d+.
    Returns (ok, bad element or NEWTON_FAILED, element work, iterations); the state reached
    in w as chang_step's.
    """
    n = len(mass)
    d, v, a = w[W_D], w[W_V], w[W_A]
    dn, vn, an = w[W_DN], w[W_VN], w[W_AN]
    pb, r, g, z = w[W_PB], w[W_R], w[W_X], w[W_Y]
    substep_load(load, j, w0, w1, w[W_PA], pb, n)
    c = 4.0 / (h * h)
    cv = 2.0 / h
    for i in range(n):
        dn[i] = d[i] + h * v[i] + 0.5 * h * h * a[i]
    follow = rot >= 0 and load.shape[1] > n  # forces whose arm turns with the body
    pb_rot = 0.0
    m3 = m4 = m5 = 0.0
    if follow:
        w[W_PA, rot] += arm_moment(load, j, w0, n, d[rot])[0]
        pb_rot = pb[rot]
    elif rot == SPATIAL:  # the moments in the body's axes at the start; at the end they turn with d+
        body_load(rotation(d[3], d[4], d[5]), load, j, w0, n, axial, w[W_PA])
        m3, m4, m5 = pb[3], pb[4], pb[5]
    for it in range(max_iter):
        ok, bad, work, kgeo = update_elements(bvec, axial, rot, mult, params, d, dn, st, cur, kpeak, r, bq, n)
        if not ok:
            return False, bad, 0.0, it + 1
        if follow:
            extra, slope = arm_moment(load, j, w1, n, dn[rot])
            pb[rot] = pb_rot + extra
            kgeo -= slope  # the load's share of the Jacobian: d(R - p)/dtheta
        elif rot == SPATIAL:
            pb[3], pb[4], pb[5] = m3, m4, m5
            body_load(turned(d, dn), load, j, w1, n, axial, pb)
        if rot == SPATIAL:
            bbt_sums(bq, mult, kpeak, 1, mass, False, wm, w[W_Q])
            add_geometric(axial, mult, st, 1 - cur, turned(d, dn), wm)
        elif rot >= 0:
            bbt_sums(bq, mult, kpeak, 1, mass, False, wm, w[W_Q])
            wm[rot, rot] += kgeo  # the rows turn with the body: the forces' geometric stiffness
        else:
            bbt_sums(bvec, mult, kpeak, 1, mass, False, wm, w[W_Q])
        for i in range(n):
            wm[i, i] += c * mass[i]
            g[i] = mass[i] * (c * (dn[i] - d[i] - h * v[i]) - a[i]) + r[i] - pb[i]
        if rot == SPATIAL:  # Euler's term at the step's end (its Jacobian, O(h omega) of M's, left out)
            for i in range(n):
                vn[i] = v[i] + 0.5 * h * (a[i] + c * (dn[i] - d[i] - h * v[i]) - a[i])
            for i in range(3, 6):
                g[i] += gyroscopic(mass, vn, i)
        if damped:
            for i in range(n):
                z[i] = cv * (dn[i] - d[i]) - v[i]
            for i in range(n):
                g[i] += row_dot(cm, i, z, n)
                for k in range(n):
                    wm[i, k] += cv * cm[i, k]
            if cm.shape[0] > n:  # dampers whose rows turn (their share of the Jacobian beyond C0 left out)
                turned_dampers(cm, rot, d, dn, z, 0, g, 1.0, n)
        # the correction x = -K^-1 g, in g
        for i in range(n):
            g[i] = -g[i]
        solve_in_place(wm, g, n)
        corr = 0.0
        incr = 0.0
        floor = 0.0
        for i in range(n):
            corr += mass[i] * g[i] * g[i]
            incr += mass[i] * (dn[i] - d[i]) ** 2
            # round-off floor: d+ itself is known to a few ulps only (a slow step's increment is tiny)
            floor += mass[i] * dn[i] * dn[i]
        floor *= ROUNDOFF2
        if corr <= tol * tol * incr + floor:
            for i in range(n):
                an[i] = c * (dn[i] - d[i] - h * v[i]) - a[i]
                vn[i] = v[i] + 0.5 * h * (a[i] + an[i])
            return True, -1, work, it + 1
        if not corr < math.inf:  # NaN or Inf: a singular Jacobian or a runaway iterate
            return False, NEWTON_FAILED, 0.0, it + 1
        for i in range(n):
            dn[i] += g[i]
    return False, NEWTON_FAILED, 0.0, max_iter
