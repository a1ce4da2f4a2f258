"""One pass over a chunk of table rows: every column's extremes and the plot buckets' extremes."""

from __future__ import annotations

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
def largest_combination(a, b, x, y, out):
    """out[e] = max_t |a[e] x[t] + b[e] y[t]| (0 without rows): each element's largest
    deformation the small rotations neglect along a run, a = b3, b = the axial offset, x =
    sin(theta) - theta, y = cos(theta) - 1 (rbhyst.solve.kinematic.model_residual). One pass
    per element, where numpy made four arrays of every element at every row."""
    for e in range(a.shape[0]):
        ae = a[e]
        be = b[e]
        top = 0.0
        for t in range(x.shape[0]):
            v = abs(ae * x[t] + be * y[t])
            if v > top:
                top = v
        out[e] = top
