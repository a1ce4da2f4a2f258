"""The adaptive integration a window of rows at a time (reference.Integration): a streamed run's
memory is a window's, and every row, count and stop is the same to the bit as the whole
integration's, however the rows are cut."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rbhyst
from conftest import DECKS, seed_deck, write_deck
from rbhyst.model.deck import load_deck
from rbhyst.results import analysis
from rbhyst.solve.integrators import reference
from rbhyst.solve.static import at_rest_under_gravity
from test_stops import launched

COUNTS = ("steps", "rejected_steps", "reversals", "branch_corrections_at_step_start", "rhs_evaluations",
          "smallest_step_s", "largest_step_s")


def pulse_deck() -> dict:
    """The seed scene under a half-sine pulse (its steps split to follow it) and a sine."""
    deck = seed_deck(duration=0.6, dt=2e-3)
    deck["excitation"]["support"]["x1"] = {"type": "half-sine", "amplitude": 3.0, "duration": 0.011,
                                           "units": "g", "start": 0.05}
    return deck


SCENES = {"seed": lambda: seed_deck(duration=1.5), "stop": lambda: launched("adaptive", 1e-3),
          "pulse": pulse_deck, "space": lambda: DECKS / "cabinet_3d.toml"}


def system_of(data, tmp_path):
    """(system at rest, settings) of a deck's mapping or file."""
    deck = load_deck(data if isinstance(data, Path) else write_deck(tmp_path, data))
    system, settings = analysis.scene(deck)
    return at_rest_under_gravity(system), settings


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_any_cut_of_the_rows_gives_the_whole_integration_to_the_bit(scene, tmp_path):
    system, settings = system_of(SCENES[scene](), tmp_path)
    t = settings.dt * np.arange(round(min(settings.duration or 1.5, 1.5) / settings.dt) + 1)
    whole = reference.integrate(system, t, 1e-9)
    for window in (1, 5, 64):
        run = reference.Integration(system, len(t), lambda lo, hi: t[lo:hi], 1e-9, window=window)
        rng = np.random.default_rng(window)
        blocks, lo = [], 0
        while lo < len(t):  # blocks shorter and longer than the window, one row or many
            lo = min(len(t), lo + int(rng.integers(1, 3 * window + 2)))
            blocks.append(run.take(lo))
        for key in ("t", "y", "eu", "ef", "eh"):
            cut = np.concatenate([getattr(b, key) for b in blocks])
            assert np.array_equal(cut, getattr(whole, key)), (window, key)
        assert {k: blocks[-1].stats[k] for k in COUNTS} == {k: whole.stats[k] for k in COUNTS}
        assert whole.stats["reversals"] > 0
        if whole.stops is not None:
            assert np.array_equal(blocks[-1].stops, whole.stops)
    if scene == "stop":
        assert whole.stops is not None and whole.stops[:, 0].max() > 0.0  # (the stop was struck)


def test_the_split_steps_times_are_the_plans(tmp_path):
    """_split_times(lo, hi) is plan.compute_times' rows, whatever the window."""
    from rbhyst.solve.plan import compute_times, grid, splitting

    system, settings = system_of(pulse_deck(), tmp_path)
    n_steps, _ = grid(system, settings)
    bounds, substeps = splitting(system, settings, n_steps)
    assert substeps.max() > 1
    full = np.concatenate([[0.0], compute_times(bounds, substeps, settings.dt)])
    times = reference._split_times(bounds, substeps, settings.dt)
    for lo, hi in ((0, len(full)), (0, 1), (3, 40), (len(full) - 7, len(full))):
        assert np.array_equal(times(lo, hi), full[lo:hi])
    rng = np.random.default_rng(0)
    for _ in range(50):
        lo = int(rng.integers(0, len(full) - 1))
        hi = int(rng.integers(lo + 1, len(full) + 1))
        assert np.array_equal(times(lo, hi), full[lo:hi])


def test_a_run_streamed_in_small_windows_is_the_run(tmp_path, monkeypatch):
    """rbhyst.run with the adaptive integrator, its steps split by a pulse and its spectra driven at
    every compute step: the same table, peaks, spectra, estimate and file with windows of 37 rows."""
    data = pulse_deck()
    data["analysis"]["integrator"] = "adaptive"
    data["output"] = {"spectra": {"damping": [0.05], "periods_s": [0.05, 0.2]}}
    path = write_deck(tmp_path, data)

    def run(out):
        res = rbhyst.run(path, out=tmp_path / out)
        kept = rbhyst.run(path)
        return res, kept, (tmp_path / out / "time_history.csv").read_bytes()

    wide, wide_kept, wide_csv = run("wide")
    monkeypatch.setattr(reference, "WINDOW_ROWS", 37)
    narrow, narrow_kept, narrow_csv = run("narrow")
    assert narrow_csv == wide_csv
    assert np.array_equal(narrow_kept.table, wide_kept.table)
    assert narrow.extremes.peaks() == wide.extremes.peaks()
    assert np.array_equal(narrow.spectra.spectrum.sa, wide.spectra.spectrum.sa)
    assert narrow.accuracy["estimated_error"] == wide.accuracy["estimated_error"]
    assert narrow.solver["steps"] == wide.solver["steps"] > 0
