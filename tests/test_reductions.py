"""Extremes and plot buckets folded chunk by chunk: the same as numpy over the whole table."""

from __future__ import annotations

import numpy as np
import pytest

from rbhyst.solve.history import Extremes, PlotData


@pytest.mark.parametrize("drawn", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chunks_of_any_size_give_numpys_extremes_and_their_first_times(seed, drawn):
    """With the plot buckets (the compiled pass) and without (a run that keeps only its
    reductions): the same extremes and times, and the last row."""
    rng = np.random.default_rng(seed)
    n, m = 5003, 6
    table = np.empty((n, m))
    table[:, 0] = 1e-3 * np.arange(n)
    table[:, 1:] = np.round(rng.normal(size=(n, m - 1)), 1)  # coarse values: many ties
    table[:, 2] = 0.0  # a column that never moves: its extremes are at t = 0
    ex = Extremes(tuple(f"c{j}" for j in range(m)))
    plot = PlotData(n, m, drawn=drawn)
    cuts = np.sort(rng.choice(np.arange(1, n), size=7, replace=False))
    for chunk in np.split(table, cuts):
        plot.update(np.asfortranarray(chunk), ex)
    assert np.array_equal(ex.max, table.max(axis=0)) and np.array_equal(ex.min, table.min(axis=0))
    assert np.array_equal(ex.t_max, table[table.argmax(axis=0), 0])  # argmax: the first of ties
    assert np.array_equal(ex.t_min, table[table.argmin(axis=0), 0])
    assert np.array_equal(plot.final, table[-1])
    if not drawn:
        with pytest.raises(ValueError, match="nothing to draw"):
            plot.series(1)
        return
    buckets = [table[k:k + plot.bucket] for k in range(0, n, plot.bucket)]
    assert np.array_equal(plot.hi, np.array([b.max(axis=0) for b in buckets]))
    assert np.array_equal(plot.lo, np.array([b.min(axis=0) for b in buckets]))
    assert np.array_equal(plot.t_lo, [b[0, 0] for b in buckets]) and np.array_equal(plot.t_hi, [b[-1, 0] for b in buckets])


def test_a_run_that_keeps_only_its_reductions_has_the_same_ones():
    """A sweep's case (rows neither kept nor written: no plot data) has the extremes, their
    times and the final energies of the same run with its rows kept, to the bit."""
    from conftest import DECKS
    from rbhyst.model.deck import load_deck
    from rbhyst.results.analysis import run_deck

    deck = load_deck(DECKS / "seed_wri.toml").with_values({"analysis.duration": 4.0})
    lean, kept = run_deck(deck, keep=False), run_deck(deck, keep=True)
    assert not lean.plot.drawn and kept.plot.drawn
    for name in ("max", "min", "t_max", "t_min"):
        assert np.array_equal(getattr(lean.extremes, name), getattr(kept.extremes, name)), name
    assert lean.energy_summary() == kept.energy_summary()
    assert lean.extremes.peaks() == kept.extremes.peaks()


def test_the_largest_combination_is_numpys_to_the_bit():
    """The kinematic check's compiled pass (rbhyst.solve.kinematic.model_residual): max_t
    |a x(t) + b y(t)| per element, the bits numpy's arrays of every element and row give."""
    from rbhyst.solve.kernels.compiled import kernel

    rng = np.random.default_rng(5)
    a, b = rng.normal(size=8), rng.normal(size=8) * 1e-3
    theta = np.cumsum(rng.normal(size=4001)) * 1e-4
    x, y = np.sin(theta) - theta, np.cos(theta) - 1.0
    out = np.empty(8)
    kernel("largest_combination")(a, b, x, y, out)
    assert np.array_equal(out, np.abs(a[:, None] * x[None, :] + b[:, None] * y[None, :]).max(axis=1))
    kernel("largest_combination")(a, b, x[:0], y[:0], out)
    assert np.array_equal(out, np.zeros(8))
