"""One pass over a chunk of table rows: every column's extremes and the plot buckets' extremes;
products of a chunk's rows summed alike for every row; every column's largest change."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, error_model="numpy", _nrt=False)
def reduce_rows(table, first, bucket, hi, t_hi, lo, t_lo, b_lo, b_hi, bt_lo, bt_hi):
    """Fold rows ``first``.. of the run (table: (n, cols), column 0 the time) into the running
    extremes hi/lo (with the first times they are reached) and the plot buckets of ``bucket``
    rows each (their smallest and largest value of every column, and their time span)."""
    n, m = table.shape
    for j in range(m):
        h = hi[j]
        th = t_hi[j]
        low = lo[j]
        tl = t_lo[j]
        s = 0
        while s < n:
            b = (first + s) // bucket
            e = min(n, (b + 1) * bucket - first)
            bl = b_lo[b, j]
            bh = b_hi[b, j]
            # the bucket's extremes without a branch per value (2-3x faster than tracking the
            # running extremes and their times value by value); a bucket that holds a new
            # extreme is searched again for the first step reaching it
            for i in range(s, e):
                x = table[i, j]
                bh = max(bh, x)
                bl = min(bl, x)
            if bh > h:  # (a value carried from the same bucket's earlier chunk is <= h already)
                for i in range(s, e):
                    if table[i, j] == bh:
                        th = table[i, 0]
                        break
                h = bh
            if bl < low:
                for i in range(s, e):
                    if table[i, j] == bl:
                        tl = table[i, 0]
                        break
                low = bl
            b_lo[b, j] = bl
            b_hi[b, j] = bh
            s = e
        hi[j] = h
        t_hi[j] = th
        lo[j] = low
        t_lo[j] = tl
    s = 0
    while s < n:
        b = (first + s) // bucket
        e = min(n, (b + 1) * bucket - first)
        if table[s, 0] < bt_lo[b]:
            bt_lo[b] = table[s, 0]
        if table[e - 1, 0] > bt_hi[b]:
            bt_hi[b] = table[e - 1, 0]
        s = e


@njit(cache=True, error_model="numpy", _nrt=False)
def neglected_terms(theta, a, b, forces, top, ra, rb, rtop):
    """The terms the seed's small rotations neglect along a run's rows (rbhyst.solve.kinematic.
    model_residual), in one pass: top[e] = max_t |a[e] s + b[e] m| (each element's deformation:
    a = b3, b = its axial offset), and the return value max_t |m sum_e f_e a_e - sin(theta)
    sum_e f_e b_e| (the moment resultant's; forces (rows, elements)), s = sin(theta) - theta,
    m = cos(theta) - 1 at each row's theta; and rtop[d] = max_t |ra[d] s + rb[d] m| (the forces'
    resultant along each deck axis d: the elements' neglected deformations at their stiffness,
    summed, ra and rb those sums).

    s and m by their series where |theta| <= 0.25 (the terms left out below 1e-15 of the sum):
    sin(theta) - theta in floating point loses the digits of theta (half of them at 1e-4 rad),
    and numpy's sin and cos were most of the check's time."""
    ne = a.shape[0]
    nr = ra.shape[0]
    for e in range(ne):
        top[e] = 0.0
    for d in range(nr):
        rtop[d] = 0.0
    worst = 0.0
    for t in range(theta.shape[0]):
        th = theta[t]
        q = th * th
        if q <= 0.0625:
            s = -th * q * (1.0 / 6.0) * (1.0 - q * (1.0 / 20.0) * (1.0 - q * (1.0 / 42.0) * (
                1.0 - q * (1.0 / 72.0) * (1.0 - q * (1.0 / 110.0) * (1.0 - q * (1.0 / 156.0))))))
            m = -q * 0.5 * (1.0 - q * (1.0 / 12.0) * (1.0 - q * (1.0 / 30.0) * (1.0 - q * (1.0 / 56.0) * (
                1.0 - q * (1.0 / 90.0) * (1.0 - q * (1.0 / 132.0))))))
        else:
            s = math.sin(th) - th
            m = math.cos(th) - 1.0
        fa = 0.0
        fb = 0.0
        for e in range(ne):
            v = abs(a[e] * s + b[e] * m)
            if v > top[e]:
                top[e] = v
            f = forces[t, e]
            fa += f * a[e]
            fb += f * b[e]
        r = abs(m * fa - (th + s) * fb)
        if r > worst:
            worst = r
        for d in range(nr):
            v = abs(s * ra[d] + m * rb[d])
            if v > rtop[d]:
                rtop[d] = v
    return worst


@njit(cache=True, error_model="numpy", _nrt=False)
def largest_change(dd, dv, df, rb, ct, damped, minv, back, turned, arms, top, w):
    """top: the largest |change| over the rows of every column the error estimate compares that
    changes dd, dv (rows, n) of the coordinates and velocities and df (rows, kernel rows) of the
    element forces make with the seed's small rotations (history.Layout.largest_change): G's
    displacement, total acceleration and the mounts' resultant (dr = df rb, dat = -M^-1 (dr +
    C dv), ct = C^T; turned to the deck's axes, x back, where ``turned``), each point's
    displacement then total acceleration along its translations (arms (points, m, n): u_P = T q,
    points.point_matrix), then every kernel row's force. w (4, n): work space. One pass, no
    array of the changes."""
    rows, n = dd.shape
    ne = df.shape[1]
    npt, m = arms.shape[0], arms.shape[1]
    body = 3 * n + 2 * m * npt
    for c in range(top.shape[0]):
        top[c] = 0.0
    d, dr, dat, z = w[0], w[1], w[2], w[3]
    for i in range(rows):
        for j in range(n):
            acc = 0.0
            for e in range(ne):
                acc += df[i, e] * rb[e, j]
            dr[j] = acc
        for j in range(n):
            x = -dr[j]
            if damped:
                acc = 0.0
                for k in range(n):
                    acc += dv[i, k] * ct[k, j]
                x -= acc
            dat[j] = x * minv[j]
            d[j] = dd[i, j]
        if turned:
            for vec in (d, dr, dat):
                for j in range(n):
                    acc = 0.0
                    for k in range(n):
                        acc += vec[k] * back[k, j]
                    z[j] = acc
                for j in range(n):
                    vec[j] = z[j]
        for j in range(n):
            top[j] = max(top[j], abs(d[j]))
            top[n + j] = max(top[n + j], abs(dat[j]))
            top[2 * n + j] = max(top[2 * n + j], abs(dr[j]))
        for p in range(npt):
            c = 3 * n + 2 * m * p
            for r in range(m):
                ud = 0.0
                ua = 0.0
                for j in range(n):
                    ud += arms[p, r, j] * d[j]
                    ua += arms[p, r, j] * dat[j]
                top[c + r] = max(top[c + r], abs(ud))
                top[c + m + r] = max(top[c + m + r], abs(ua))
        for e in range(ne):
            top[body + e] = max(top[body + e], abs(df[i, e]))


@njit(cache=True, error_model="numpy", _nrt=False)
def resultant(f, rb, out):
    """out (rows, m) = f rb (f: rows, k; rb: k, m): each row's sum over k in that order whatever
    the number of rows (history.rows_times: the mounts' resultant, the viscous forces, the
    dampers' rates). A BLAS product sums a single row (a matrix times a vector) in another
    order than a block of rows on some processors (on an AMD EPYC 201 of 279 rows of the
    seed's resultant differed in their last bit): a run's rows would depend on where its
    chunks start."""
    for i in range(f.shape[0]):
        for j in range(rb.shape[1]):
            acc = 0.0
            for e in range(f.shape[1]):
                acc += f[i, e] * rb[e, j]
            out[i, j] = acc
