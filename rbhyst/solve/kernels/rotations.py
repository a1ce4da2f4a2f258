"""Finite rotations in space for the compiled kernels: the rotation vector, its matrix and back.

A body in space with exact kinematics (rbhyst.model.rotations) carries its attitude as the
rotation vector psi (R = exp([psi]x), Rodrigues' formula) and its angular velocity omega in the
body's own axes, so that M = diag(m, m, m, J) stays constant and J omega' + omega x J omega is
Euler's equation. A step of any method advances psi by composing the turn it takes, its
increment Delta (body axes), on the right: R+ = R(psi) exp([Delta]x) (Simo and Vu-Quoc's
material form of Newmark's method). Matrices are 9-tuples, row by row (registers, no memory).
"""

from __future__ import annotations

import math

from numba import njit

#: below this angle (rad) the series of sin(x)/x and (1 - cos x)/x^2 are used: their next terms are
#: below round-off there
SMALL_ANGLE = 1e-4


@njit(cache=True, error_model="numpy", _nrt=False)
def rotation(p0, p1, p2):
    """R = exp([p]x) of the rotation vector p (Rodrigues' formula), as a 9-tuple row by row."""
    t2 = p0 * p0 + p1 * p1 + p2 * p2
    if t2 < SMALL_ANGLE * SMALL_ANGLE:
        a = 1.0 - t2 / 6.0
        b = 0.5 - t2 / 24.0
    else:
        t = math.sqrt(t2)
        a = math.sin(t) / t
        half = math.sin(0.5 * t)
        b = 2.0 * half * half / t2  # (1 - cos t) / t^2 without cancellation
    # R = I + a [p]x + b [p]x^2, [p]x^2 = p p^T - t^2 I
    return (1.0 + b * (p0 * p0 - t2), b * p0 * p1 - a * p2, b * p0 * p2 + a * p1,
            b * p1 * p0 + a * p2, 1.0 + b * (p1 * p1 - t2), b * p1 * p2 - a * p0,
            b * p2 * p0 - a * p1, b * p2 * p1 + a * p0, 1.0 + b * (p2 * p2 - t2))


@njit(cache=True, error_model="numpy", _nrt=False)
def product(a, b):
    """The 3x3 product a b of two 9-tuples."""
    return (a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
            a[0] * b[2] + a[1] * b[5] + a[2] * b[8],
            a[3] * b[0] + a[4] * b[3] + a[5] * b[6], a[3] * b[1] + a[4] * b[4] + a[5] * b[7],
            a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
            a[6] * b[2] + a[7] * b[5] + a[8] * b[8])


@njit(cache=True, error_model="numpy", _nrt=False)
def rotation_vector(r):
    """The rotation vector psi (|psi| <= pi) of the rotation matrix r (9-tuple): the inverse of
    ``rotation``. From the skew part where the angle is below pi / 2, from the symmetric part
    near pi (where the skew part vanishes)."""
    c = 0.5 * (r[0] + r[4] + r[8] - 1.0)  # cos t
    s0 = 0.5 * (r[7] - r[5])
    s1 = 0.5 * (r[2] - r[6])
    s2 = 0.5 * (r[3] - r[1])
    s = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)  # sin t, t in [0, pi]
    if c > 0.0:
        t = math.atan2(s, c)
        f = 1.0 + s * s / 6.0 if s < SMALL_ANGLE else t / s  # asin-like series of t / sin t
        return f * s0, f * s1, f * s2
    # near pi: R + R^T = 2 cos t I + 2 (1 - cos t) n n^T gives the axis n, signed by the skew part
    t = math.atan2(s, c)
    k = 1.0 - c
    n0 = math.sqrt(max(0.0, (r[0] - c) / k))
    n1 = math.sqrt(max(0.0, (r[4] - c) / k))
    n2 = math.sqrt(max(0.0, (r[8] - c) / k))
    # signs relative to the largest component, from the off-diagonal sums
    if n0 >= n1 and n0 >= n2:
        n1 = math.copysign(n1, r[1] + r[3])
        n2 = math.copysign(n2, r[2] + r[6])
        sign = 1.0 if s0 >= 0.0 else -1.0
    elif n1 >= n2:
        n0 = math.copysign(n0, r[1] + r[3])
        n2 = math.copysign(n2, r[5] + r[7])
        sign = 1.0 if s1 >= 0.0 else -1.0
    else:
        n0 = math.copysign(n0, r[2] + r[6])
        n1 = math.copysign(n1, r[5] + r[7])
        sign = 1.0 if s2 >= 0.0 else -1.0
    return sign * t * n0, sign * t * n1, sign * t * n2


@njit(cache=True, error_model="numpy", _nrt=False)
def turned(q0, q):
    """The attitude a step reaches: R(psi0) exp([Delta]x), psi0 = q0[3:6] where the step starts
    and Delta = q[3:6] - q0[3:6] the turn it takes in the body's axes (a step writes its state as
    q0 + increment; the loop composes it when the step is accepted, ``compose``)."""
    r0 = rotation(q0[3], q0[4], q0[5])
    return product(r0, rotation(q[3] - q0[3], q[4] - q0[4], q[5] - q0[5]))


@njit(cache=True, error_model="numpy", _nrt=False)
def compose(q0, q):
    """q[3:6] := the rotation vector of R(psi0) exp([Delta]x) (see ``turned``)."""
    p0, p1, p2 = rotation_vector(turned(q0, q))
    q[3] = p0
    q[4] = p1
    q[5] = p2


@njit(cache=True, error_model="numpy", _nrt=False)
def turn_moments(r, p, f0, f1, f2, axial):
    """p[3:6] := R^T (m - r_p x f) + r_p x (R^T f) (see ``body_load``; f = 0 where no force
    acts away from G)."""
    k = len(axial) - 3
    x0, x1, x2 = axial[k], axial[k + 1], axial[k + 2]
    m0 = p[3] - (x1 * f2 - x2 * f1)
    m1 = p[4] - (x2 * f0 - x0 * f2)
    m2 = p[5] - (x0 * f1 - x1 * f0)
    g0 = r[0] * f0 + r[3] * f1 + r[6] * f2
    g1 = r[1] * f0 + r[4] * f1 + r[7] * f2
    g2 = r[2] * f0 + r[5] * f1 + r[8] * f2
    p[3] = r[0] * m0 + r[3] * m1 + r[6] * m2 + (x1 * g2 - x2 * g1)
    p[4] = r[1] * m0 + r[4] * m1 + r[7] * m2 + (x2 * g0 - x0 * g2)
    p[5] = r[2] * m0 + r[5] * m1 + r[8] * m2 + (x0 * g1 - x1 * g0)


@njit(cache=True, error_model="numpy", _nrt=False)
def body_load(r, load, j, w, n, axial, p):
    """The load's moments p[3:6] (about G, in the ground's axes) turned into the body's at the
    attitude r (9-tuple): R^T m; where forces act away from G (load columns n..n+2: their
    components along the kernels' axes, at the fraction w of compute step j) their arm r_p
    (axial's last three entries) turns with the body: the moment r_p x (R^T f) replaces the
    r_p x f the load carries."""
    f0 = f1 = f2 = 0.0
    if load.shape[1] > n:
        f0 = load[j, n] + w * (load[j + 1, n] - load[j, n])
        f1 = load[j, n + 1] + w * (load[j + 1, n + 1] - load[j, n + 1])
        f2 = load[j, n + 2] + w * (load[j + 1, n + 2] - load[j, n + 2])
    turn_moments(r, p, f0, f1, f2, axial)


@njit(cache=True, error_model="numpy", _nrt=False)
def arm(axial, e, r):
    """What element row e's point and line (x', d': axial[6 e:6 e + 6], in the kernels' rotation
    axes) give at the attitude r (9-tuple): (d' . (R x' - x'), the three components of
    x' x R^T d', and of R^T d'): its deformation's share of the turn, its row's rotation entries
    and its line in the body's axes."""
    k = 6 * e
    x0, x1, x2 = axial[k], axial[k + 1], axial[k + 2]
    c0, c1, c2 = axial[k + 3], axial[k + 4], axial[k + 5]
    y0 = r[0] * x0 + r[1] * x1 + r[2] * x2 - x0
    y1 = r[3] * x0 + r[4] * x1 + r[5] * x2 - x1
    y2 = r[6] * x0 + r[7] * x1 + r[8] * x2 - x2
    a0 = r[0] * c0 + r[3] * c1 + r[6] * c2
    a1 = r[1] * c0 + r[4] * c1 + r[7] * c2
    a2 = r[2] * c0 + r[5] * c1 + r[8] * c2
    return (c0 * y0 + c1 * y1 + c2 * y2, x1 * a2 - x2 * a1, x2 * a0 - x0 * a2, x0 * a1 - x1 * a0, a0, a1, a2)


@njit(cache=True, error_model="numpy", _nrt=False)
def element_row(bvec, axial, e, r, q, bq):
    """Element row e at the attitude r (9-tuple) and q: its deformation d . (u + R x - x) and its
    row b_e(q) = (d, x' x R^T d') into bq[e] (d: bvec[e, :3], in the kernels' translation axes;
    see ``arm``)."""
    t = arm(axial, e, r)
    bq[e, 0] = bvec[e, 0]
    bq[e, 1] = bvec[e, 1]
    bq[e, 2] = bvec[e, 2]
    bq[e, 3] = t[1]
    bq[e, 4] = t[2]
    bq[e, 5] = t[3]
    return bvec[e, 0] * q[0] + bvec[e, 1] * q[1] + bvec[e, 2] * q[2] + t[0]


@njit(cache=True, error_model="numpy", _nrt=False)
def centripetal(axial, e, t, w0, w1, w2):
    """The part of element e's deformation acceleration the rows leave out: (R^T d') . (omega x
    (omega x x')), t = arm(axial, e, R), omega in the body's axes."""
    k = 6 * e
    x0, x1, x2 = axial[k], axial[k + 1], axial[k + 2]
    v0 = w1 * x2 - w2 * x1
    v1 = w2 * x0 - w0 * x2
    v2 = w0 * x1 - w1 * x0
    return t[4] * (w1 * v2 - w2 * v1) + t[5] * (w2 * v0 - w0 * v2) + t[6] * (w0 * v1 - w1 * v0)


@njit(cache=True, error_model="numpy", _nrt=False)
def attitude_rate(p0, p1, p2, w0, w1, w2):
    """d psi / dt for the body's angular velocity omega (its own axes): J_r(psi)^-1 omega =
    omega + psi x omega / 2 + beta psi x (psi x omega), beta = (1 - (t/2) cot(t/2)) / t^2
    (t = |psi| < 2 pi)."""
    t2 = p0 * p0 + p1 * p1 + p2 * p2
    if t2 < 1e-4:
        beta = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    else:
        t = math.sqrt(t2)
        beta = (1.0 - 0.5 * t / math.tan(0.5 * t)) / t2
    c0 = p1 * w2 - p2 * w1
    c1 = p2 * w0 - p0 * w2
    c2 = p0 * w1 - p1 * w0
    return (w0 + 0.5 * c0 + beta * (p1 * c2 - p2 * c1), w1 + 0.5 * c1 + beta * (p2 * c0 - p0 * c2),
            w2 + 0.5 * c2 + beta * (p0 * c1 - p1 * c0))


@njit(cache=True, error_model="numpy", _nrt=False)
def gyroscopic(mass, v, i):
    """Component i (3, 4, 5) of omega x J omega, omega = v[3:6] in the body's principal axes,
    J = diag(mass[3:6]) (mass a tuple of n = 6; its indices are not literals, so that the plane's
    n = 3 compiles the branch it never takes)."""
    k = len(mass) - 3
    j0, j1, j2 = mass[k], mass[k + 1], mass[k + 2]
    if i == 3:
        return (j2 - j1) * v[4] * v[5]
    if i == 4:
        return (j0 - j2) * v[5] * v[3]
    return (j1 - j0) * v[3] * v[4]


@njit(cache=True, error_model="numpy", _nrt=False)
def add_geometric(axial, mult, st, nxt, r, wm):
    """Add the elements' geometric stiffness to wm[3:6, 3:6]: the change of their moments
    sum mult f x' x R^T d' as the body turns by delta in its own axes (R -> R exp([delta]x)),
    -sum mult f ((x' . a) I - a x'^T), a = R^T d' (Newmark's Newton matrix: with it the
    iterations converge quadratically; st[nxt, e, 1]: each row's force)."""
    for e in range(len(mult)):
        t = arm(axial, e, r)
        k = 6 * e
        x0, x1, x2 = axial[k], axial[k + 1], axial[k + 2]
        a0, a1, a2 = t[4], t[5], t[6]
        mf = mult[e] * st[nxt, e, 1]
        xa = x0 * a0 + x1 * a1 + x2 * a2
        wm[3, 3] -= mf * (xa - a0 * x0)
        wm[3, 4] += mf * a0 * x1
        wm[3, 5] += mf * a0 * x2
        wm[4, 3] += mf * a1 * x0
        wm[4, 4] -= mf * (xa - a1 * x1)
        wm[4, 5] += mf * a1 * x2
        wm[5, 3] += mf * a2 * x0
        wm[5, 4] += mf * a2 * x1
        wm[5, 5] -= mf * (xa - a2 * x2)
