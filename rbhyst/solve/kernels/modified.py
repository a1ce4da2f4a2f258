"""The companion's load and starting velocity from a run's accelerations, in one pass over its
compute nodes (rbhyst.solve.companion states the formulas and what they come from).

A' and A'' by three-point differences on the uneven grid of the nodes (one-sided second-order
at the ends for A', zero for A'' there); then at every node, with hh = h^2 of the step the
loop takes after it,

    newmark             -S = -hh M A''/6 - hh C A'/12,            q' - V = hh A'/12
    central difference  -S = hh M A''/12 + hh C A'/6,             q' - V = -hh A'/6
    chang               -S = hh [M A''/12 + K0 A/4 + 5/12 C A'      q' - V = -hh [A'/6 + M^-1 (C A + K0 V)/4]
                              + C M^-1 (C A + K0 V)/4],
"""

from __future__ import annotations

import math

from numba import njit

from rbhyst.solve.kernels.layout import MODIFIED

NEWMARK, CENTRAL_DIFFERENCE, CHANG = MODIFIED["newmark"], MODIFIED["central-difference"], MODIFIED["chang"]


@njit(cache=True, error_model="numpy", _nrt=False)
def companion_source(method, load, v, f, a0, rb, c, damped, minv, mass, k0, t, levels, bounds, substeps, dt, breaks,
                     a, h, near, extra, offset, d1, d2, w1):
    """source_and_offset from a run's rows at its compute nodes t (the seed's small rotations):
    the method's accelerations a = M^-1 (p - R - C V) with R = f rb (node 0's, a0, the loop's
    own at rest), each node's step h = dt / nsub / 2^level (output steps bounds[i]..bounds[i +
    1] take substeps[i] compute steps each, each compute step at its ``levels``; the last node's
    the one before it) and the nodes ``near`` within 1.5 h of a signal's start, end or corner
    (``breaks``), all written into the arrays given."""
    nn = a.shape[0]
    i = 0
    for s in range(substeps.shape[0]):
        base = dt / substeps[s]
        for _ in range((bounds[s + 1] - bounds[s]) * substeps[s]):
            h[i] = math.ldexp(base, -int(levels[i]))  # (exact: a power of two)
            i += 1
    h[nn - 1] = h[nn - 2] if nn > 1 else dt
    window_source(method, load, v, f, a0, rb, c, damped, minv, mass, k0, t, h, breaks, a, near, extra, offset,
                  d1, d2, w1)


@njit(cache=True, error_model="numpy", _nrt=False)
def window_source(method, load, v, f, a0, rb, c, damped, minv, mass, k0, t, h, breaks, a, near, extra, offset,
                  d1, d2, w1):
    """companion_source of consecutive compute nodes with their steps h given: a0 the
    acceleration at the first (the loop's own where it is node 0, the one this pass found where
    it is a later window's: rbhyst.solve.alongside). A node with both neighbours in the window
    gets what it gets from the whole run's, to the bit; the window's ends get the run's ends'
    one-sided differences."""
    nn, n = a.shape
    ne = f.shape[1]
    for j in range(n):
        a[0, j] = a0[j]
    for i in range(1, nn):
        for j in range(n):
            r = 0.0
            for e in range(ne):
                r += f[i, e] * rb[e, j]
            x = load[i, j] - r
            if damped:
                cv = 0.0
                for k in range(n):
                    cv += v[i, k] * c[j, k]
                x -= cv
            a[i, j] = x * minv[j]
    for i in range(nn):
        near[i] = False
        for b in breaks:
            if abs(t[i] - b) <= 1.5 * h[i]:
                near[i] = True
    source_and_offset(method, a, v, t, h, mass, c, damped, k0, near, extra, offset, d1, d2, w1)


@njit(cache=True, error_model="numpy", _nrt=False)
def source_and_offset(method, a, v, t, h, mass, c, damped, k0, near, extra, offset, d1, d2, w1):
    """extra (N, n) = -S at the nodes (0 where ``near``), offset (N, n) = q' - V (module
    docstring) from the method's accelerations a and velocities v (N, n) at the nodes t, h the
    step after each; c: C (any (n, n) where not ``damped``). d1, d2, w1 (n,): work space."""
    nn, n = a.shape
    for i in range(nn):
        if nn < 3:
            for j in range(n):
                d1[j] = 0.0
                d2[j] = 0.0
        elif i == 0:
            for j in range(n):
                d1[j] = (-1.5 * a[0, j] + 2.0 * a[1, j] - 0.5 * a[2, j]) / (t[1] - t[0])
                d2[j] = 0.0
        elif i == nn - 1:
            for j in range(n):
                d1[j] = (1.5 * a[i, j] - 2.0 * a[i - 1, j] + 0.5 * a[i - 2, j]) / (t[i] - t[i - 1])
                d2[j] = 0.0
        else:
            # three divisions a node, not four a coordinate (they were most of the pass)
            hl = t[i] - t[i - 1]
            hr = t[i + 1] - t[i]
            ihl = 1.0 / hl
            ihr = 1.0 / hr
            ihs = 1.0 / (hl + hr)
            for j in range(n):
                sl = (a[i, j] - a[i - 1, j]) * ihl
                sr = (a[i + 1, j] - a[i, j]) * ihr
                d2[j] = 2.0 * (sr - sl) * ihs
                d1[j] = (hl * sr + hr * sl) * ihs
        hh = h[i] * h[i]
        if method == CHANG:
            # w1 = M^-1 (C A + K0 V)
            for j in range(n):
                acc = 0.0
                for k in range(n):
                    acc += k0[j, k] * v[i, k]
                    if damped:
                        acc += c[j, k] * a[i, k]
                w1[j] = acc / mass[j]
            for j in range(n):
                ka = 0.0
                cc = 0.0
                for k in range(n):
                    ka += k0[j, k] * a[i, k]
                    if damped:
                        cc += c[j, k] * ((5.0 / 12.0) * d1[k] + 0.25 * w1[k])
                extra[i, j] = hh * (d2[j] * mass[j] * (1.0 / 12.0) + 0.25 * ka + cc)
                offset[i, j] = -hh * (d1[j] * (1.0 / 6.0) + 0.25 * w1[j])
        else:
            sign = -1.0 if method == NEWMARK else 1.0
            fm = 1.0 / 6.0 if method == NEWMARK else 1.0 / 12.0
            fc = 1.0 / 12.0 if method == NEWMARK else 1.0 / 6.0
            for j in range(n):
                cd = 0.0
                if damped:
                    for k in range(n):
                        cd += c[j, k] * d1[k]
                extra[i, j] = sign * hh * (fm * d2[j] * mass[j] + fc * cd)
                offset[i, j] = -sign * fc * hh * d1[j]
        if near[i]:
            for j in range(n):
                extra[i, j] = 0.0
