"""Extremes and plot buckets folded chunk by chunk: the same as numpy over the whole table."""

from __future__ import annotations

import numpy as np
import pytest

from rbhyst.solve.history import Extremes, PlotData


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chunks_of_any_size_give_numpys_extremes_and_their_first_times(seed):
    rng = np.random.default_rng(seed)
    n, m = 5003, 6
    table = np.empty((n, m))
    table[:, 0] = 1e-3 * np.arange(n)
    table[:, 1:] = np.round(rng.normal(size=(n, m - 1)), 1)  # coarse values: many ties
    table[:, 2] = 0.0  # a column that never moves: its extremes are at t = 0
    ex = Extremes(tuple(f"c{j}" for j in range(m)))
    plot = PlotData(n, m)
    cuts = np.sort(rng.choice(np.arange(1, n), size=7, replace=False))
    for chunk in np.split(table, cuts):
        plot.update(np.asfortranarray(chunk), ex)
    assert np.array_equal(ex.max, table.max(axis=0)) and np.array_equal(ex.min, table.min(axis=0))
    assert np.array_equal(ex.t_max, table[table.argmax(axis=0), 0])  # argmax: the first of ties
    assert np.array_equal(ex.t_min, table[table.argmin(axis=0), 0])
    buckets = [table[k:k + plot.bucket] for k in range(0, n, plot.bucket)]
    assert np.array_equal(plot.hi, np.array([b.max(axis=0) for b in buckets]))
    assert np.array_equal(plot.lo, np.array([b.min(axis=0) for b in buckets]))
    assert np.array_equal(plot.t_lo, [b[0, 0] for b in buckets]) and np.array_equal(plot.t_hi, [b[-1, 0] for b in buckets])
