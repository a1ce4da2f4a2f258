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
            for i in range(s, e):
                x = table[i, j]
                if x > bh:
                    bh = x
                    if x > h:
                        h = x
                        th = table[i, 0]
                if x < bl:
                    bl = x
                    if x < low:
                        low = x
                        tl = table[i, 0]
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
