"""Extremes and plot buckets folded chunk by chunk: the same as numpy over the whole table."""

from __future__ import annotations

import math

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


def test_the_neglected_terms_are_numpy_s_to_rounding():
    """The kinematic check's compiled pass (rbhyst.solve.kinematic.model_residual): each
    element's largest neglected deformation max_t |b3 (sin theta - theta) + c (cos theta - 1)|
    and the moment resultant's, as numpy's arrays give them where theta is large enough for
    sin(theta) - theta to keep its digits, and its series where it is not (the small angles
    of a run, and past the series' 0.25 rad)."""
    from rbhyst.solve.kernels.compiled import kernel

    rng = np.random.default_rng(5)
    a, b = rng.normal(size=8), rng.normal(size=8) * 1e-2
    forces = rng.normal(size=(4001, 8)) * 1e3
    for scale in (1e-4, 0.05, 0.3):
        theta = np.cumsum(rng.normal(size=4001)) * scale / 60
        exact = scale < 0.01  # (numpy's sin(theta) - theta and cos(theta) - 1 lose their digits)
        s = np.array([sin_minus_x(x) for x in theta]) if exact else np.sin(theta) - theta
        m = np.array([cos_minus_one(x) for x in theta]) if exact else np.cos(theta) - 1.0
        top, along = np.empty(8), np.empty(2)
        ra, rb = rng.normal(size=2) * 1e5, rng.normal(size=2) * 1e3
        dr = kernel("neglected_terms")(theta, a, b, forces, top, ra, rb, along)
        want = np.abs(a[:, None] * s[None, :] + b[:, None] * m[None, :]).max(axis=1)
        assert np.allclose(top, want, rtol=1e-12, atol=0), scale
        want_r = np.abs(m * (forces @ a) - (theta + s) * (forces @ b)).max()
        assert abs(dr - want_r) <= 1e-12 * want_r, scale
        want_axes = np.abs(ra[:, None] * s[None, :] + rb[:, None] * m[None, :]).max(axis=1)
        assert np.allclose(along, want_axes, rtol=1e-12, atol=0), scale
    along[:] = 1.0
    assert kernel("neglected_terms")(theta[:0], a, b, forces[:0], top, ra, rb, along) == 0.0
    assert not top.any() and not along.any()


def sin_minus_x(x: float) -> float:
    """sin(x) - x without the cancellation: its series to x^15, summed smallest first."""
    terms = [(-1) ** k * x ** (2 * k + 1) / math.factorial(2 * k + 1) for k in range(1, 8)]
    return sum(reversed(terms))


def cos_minus_one(x: float) -> float:
    """cos(x) - 1 without the cancellation: its series to x^14, summed smallest first."""
    terms = [(-1) ** k * x ** (2 * k) / math.factorial(2 * k) for k in range(1, 8)]
    return sum(reversed(terms))
