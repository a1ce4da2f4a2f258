"""A stop (a snubber, a bumper, a contact with the ground): Walton and Braun's linear loading and
unloading law, compiled for the time-stepping loops.

Beyond its gap an element bears on the stop. With d the penetration past the gap and d_max its
largest in the current contact (Walton, O. R. and Braun, R. L., 1986, "Viscosity, granular
temperature, and stress calculations for shearing assemblies of inelastic, frictional disks",
Journal of Rheology 30, 949-980):

- loading (d = d_max, growing): F = K d;
- unloading and reloading below d_max: F = (K / e^2) (d - d_max (1 - e^2)), and 0 below
  d_max (1 - e^2);
- the contact ends where d returns to 0 (past the gap): d_max is reset.

The law is rate-independent, like the VRM (no velocity in the force, so a run's answer does not
hang on how fast a step approaches), a mass hitting it rebounds with exactly e, and each impact
loses 0.5 K d_max^2 (1 - e^2). The work done on the stop so far is the energy it holds,
0.5 (K / e^2) (d - d_max (1 - e^2))^2 on the unloading line, plus what its impacts lost.

One state per side: d_max of its current contact (0 outside one). The stop's parameters are the
kernels' third parameter row of an element (rbhyst.model.hysteresis ``STOP_*``;
rbhyst.model.system.System.kernel_params).
"""

from __future__ import annotations

from numba import njit

from rbhyst.model.hysteresis import STOP_E, STOP_K, STOP_LOWER, STOP_ROW, STOP_UPPER  # noqa: F401 (the kernels')


@njit(cache=True, error_model="numpy", inline="always")
def _held(d, m, kr, r):
    """The energy the stop holds at penetration d below the peak m: 0.5 (K / e^2) (d - m (1 - e^2))^2 on
    its unloading line, 0 off it."""
    x = d - m * (1.0 - r * r)
    return 0.5 * kr * x * x if x > 0.0 and d > 0.0 else 0.0


@njit(cache=True, error_model="numpy", inline="always")
def stop_side(d0, d1, m0, k, r):
    """One side of a stop over a step along which the penetration goes monotonically from d0 to d1,
    m0 the peak of the current contact (0 outside one). Returns (force at d1 (>= 0), the peak
    after the step (0 where the contact ended), the largest tangent over the step, the tangent
    at its end, the work of the force over the step, the energy the step's impact lost, whether
    a contact began)."""
    if d0 <= 0.0 and d1 <= 0.0 and m0 == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False
    kr = k / (r * r)
    m = max(m0, d1)
    loss = 0.5 * k * (1.0 - r * r) * (m * m - m0 * m0)
    work = _held(d1, m, kr, r) - _held(d0, m0, kr, r) + loss
    f1 = 0.0
    if d1 > 0.0:
        f1 = max(0.0, kr * (d1 - m * (1.0 - r * r)))
    f0 = 0.0
    if d0 > 0.0:
        f0 = max(0.0, kr * (d0 - m0 * (1.0 - r * r)))
    k_end = 0.0
    if d1 > 0.0 and d1 >= m0:
        k_end = k  # on the loading line
    elif f1 > 0.0:
        k_end = kr
    k_top = k_end
    if (f0 > 0.0 or f1 > 0.0) and min(d0, d1) < m0:  # the step ran along the unloading line
        k_top = max(k_top, kr)
    if d1 > max(m0, 0.0):
        k_top = max(k_top, k)
    began = m0 == 0.0 and d0 <= 0.0 < d1
    if d1 <= 0.0:
        m = 0.0  # back past the gap: the contact is over
    return f1, m, k_top, k_end, work, loss, began


@njit(cache=True, error_model="numpy", inline="always")
def stop_update(p, e, u0, u1, ml, mu):
    """Element e's stop (its parameters in p[e, STOP_ROW]) over a step of its deformation from u0 to
    u1, ml and mu the peaks of the lower and upper side's contacts. Returns (the stop's force on
    the element at u1 (positive pushes back a positive deformation), the peaks after, the largest
    tangent over the step, the tangent at its end, the work, the energy lost, whether a contact
    began, whether the stop took part at all (where not, every number is 0))."""
    k = p[e, STOP_ROW, STOP_K]
    if k == 0.0:
        return 0.0, ml, mu, 0.0, 0.0, 0.0, 0.0, False, False
    r = p[e, STOP_ROW, STOP_E]
    lo = p[e, STOP_ROW, STOP_LOWER]
    hi = p[e, STOP_ROW, STOP_UPPER]
    fu, mu1, ku, keu, wu, lu, bu = stop_side(u0 - hi, u1 - hi, mu, k, r)
    fl, ml1, kl, kel, wl, ll, bl = stop_side(lo - u0, lo - u1, ml, k, r)
    engaged = ku != 0.0 or kl != 0.0 or fu != 0.0 or fl != 0.0 or mu != 0.0 or ml != 0.0
    return fu - fl, ml1, mu1, ku + kl, keu + kel, wu + wl, lu + ll, bu or bl, engaged


@njit(cache=True, error_model="numpy", inline="always")
def stop_force(p, e, u, ml, mu):
    """The stop's force on element e at deformation u, the peaks ml, mu held so far (the adaptive
    reference's, along a step it takes monotonically: the peak is the larger of the held and u's),
    and the work done on it so far in this contact (held energy plus the contact's loss)."""
    k = p[e, STOP_ROW, STOP_K]
    if k == 0.0:
        return 0.0, 0.0
    r = p[e, STOP_ROW, STOP_E]
    kr = k / (r * r)
    f = 0.0
    w = 0.0
    for side in range(2):
        d = u - p[e, STOP_ROW, STOP_UPPER] if side == 1 else p[e, STOP_ROW, STOP_LOWER] - u
        m0 = mu if side == 1 else ml
        if d <= 0.0 and m0 == 0.0:
            continue
        m = max(m0, d)
        fs = max(0.0, kr * (d - m * (1.0 - r * r))) if d > 0.0 else 0.0
        f += fs if side == 1 else -fs
        w += _held(d, m, kr, r) + 0.5 * k * (1.0 - r * r) * m * m
    return f, w
