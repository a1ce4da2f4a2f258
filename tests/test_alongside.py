"""The companion stepped alongside a long run, a chunk behind it (rbhyst.solve.alongside): the
estimate of the companion that keeps the whole run (rbhyst.solve.companion), bit for bit, in
arrays of a chunk's size whatever the run's length."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rbhyst
from conftest import DECKS, seed_deck, write_deck

METHODS = ["chang", "central-difference", "newmark"]


def scene_path(tmp_path, name: str):
    """Scenes that take every path of the companion: the seed deck (no step split: the forces
    are its rows'), the seed's scene at 2 ms near its warning (the probe runs; the monitor splits
    steps: the forces are re-driven between the rows), a shock that splits the steps around it in
    14 (segments of another splitting), Rayleigh damping with points, and a random scene of
    stiffening elements whose steps the monitor splits."""
    if name == "seed deck":
        return DECKS / "seed_wri.toml"
    return write_deck(tmp_path, scene_data(name))


def scene_data(name: str) -> dict:
    if name == "monitor splits":
        from test_accuracy import random_scene

        data = random_scene(np.random.default_rng(1021))
        data["analysis"]["kinematics"] = "small"
        return data
    data = seed_deck(duration=0.6, dt=2e-3, warn_error=1e-4, kinematics="small")
    if name == "shock split in 14":
        data["excitation"] = {"support": {"x1": {"type": "half-sine", "amplitude": 20.0, "units": "g",
                                                 "duration": 0.0061, "start": 0.0507}}}
    elif name == "damped with points":
        data["damping"] = {"rayleigh": {"ratio": 0.05, "modes": [1, 2]}}
        data["output"] = {"points": [{"name": "top", "point": [0.3, 1.0]}, {"name": "side", "point": [-0.7, 0.0]}]}
    return data


def _streamed(monkeypatch, on: bool) -> None:
    from rbhyst.solve import companion

    monkeypatch.setattr(companion, "WHOLE_RUN_BYTES", 0 if on else 10**15)


@pytest.mark.parametrize("name", ["seed deck", "seed", "shock split in 14", "damped with points", "monitor splits"])
@pytest.mark.parametrize("method", METHODS)
def test_a_streamed_run_s_estimate_is_the_in_memory_run_s_to_the_bit(tmp_path, monkeypatch, name, method):
    """rbhyst.run(deck, out=...) with its companion alongside (every run streamed so) and
    rbhyst.run(deck) with the whole run's companion give the same accuracy, every number of it
    (estimated errors, the probe's spread, status, method) but the seconds."""
    path = scene_path(tmp_path, name)
    _streamed(monkeypatch, False)
    whole = rbhyst.run(path, integrator=method).accuracy
    _streamed(monkeypatch, True)
    out = tmp_path / "out"
    rbhyst.run(path, integrator=method, out=out, plots=False)
    streamed = json.loads((out / "summary.json").read_text())["accuracy"]
    whole = json.loads(json.dumps(whole))  # (summary.json's numbers: the same floats, as JSON writes them)
    for acc in (whole, streamed):
        acc.pop("wall_s")
        for key in ("wall_s", "steps"):
            acc.get("companion", {}).pop(key, None)
    assert streamed == whole
    if method == "chang":  # (the scenes are chosen so that the companion says it, with its check)
        assert "spread" in whole["companion"], whole["method"]
    assert streamed["status"] == "estimated" and ("companion" in streamed or method != "chang")


@pytest.mark.parametrize("name, splits", [("seed deck", False), ("monitor splits", True), ("shock split in 14", True)])
def test_the_scenes_reach_the_split_steps_and_the_segments(tmp_path, name, splits):
    """The scenes above reach what they are meant to: the monitor's split steps (where the
    forces are re-driven) or segments of 14 compute steps a step of dt."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.alongside import Alongside
    from rbhyst.solve.plan import compare_stride

    system, settings = scene(rbhyst.load_deck(scene_path(tmp_path, name)), integrator="chang")
    planned = plan(system, settings)
    tap = Alongside(planned, compare_stride(planned.layout, planned.compute_steps))
    planned.run(keep=False, tap=tap)
    assert tap.nodes.split == splits
    assert (planned.substeps.max() == 14) == (name == "shock split in 14")


@pytest.mark.parametrize("beside", [False, True])
@pytest.mark.parametrize("chunk", [1, 2, 7])
@pytest.mark.parametrize("name", ["seed", "shock split in 14", "monitor splits"])
def test_the_estimate_alongside_does_not_depend_on_where_the_chunks_end(tmp_path, monkeypatch, chunk, name, beside):
    """Chunks of 1, 2 and 7 compute steps (a first chunk too short for the source's differences,
    whose nodes wait; a piece of the companion across a change of splitting; a turn patched
    across every chunk's start), the companion and the probe in the run's thread or on one of
    their own a chunk behind: the estimate of the whole run's companion, to the bit."""
    from rbhyst.results.analysis import analyse, plan, scene

    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, scene_data(name))), integrator="chang")
    _streamed(monkeypatch, False)
    whole = analyse(system, settings, keep=False, spare_core=False).accuracy
    _streamed(monkeypatch, True)
    planned = plan(system, settings)
    planned.fine_chunk = chunk
    streamed = analyse(system, settings, keep=False, planned=planned, spare_core=beside).accuracy
    assert "companion" in whole and "companion" in streamed
    assert streamed["estimated_error"] == whole["estimated_error"]
    assert streamed["companion"].get("spread") == whole["companion"].get("spread")


def test_what_the_estimate_alongside_keeps_does_not_grow_with_the_run(tmp_path):
    """The seed deck's run of N and of 4N compute steps (chunks of 1000 steps): the tap and its
    companion keep arrays of the same bytes, about a chunk's, where the whole run's tap grows
    fourfold; both estimates are the companion's."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.alongside import Alongside
    from rbhyst.solve.companion import RunTap
    from rbhyst.solve.estimate import estimate
    from rbhyst.solve.plan import compare_stride

    deck = rbhyst.load_deck(DECKS / "seed_wri.toml")
    kept, whole = [], []
    for duration in (2.0, 8.0):
        system, settings = scene(deck.with_values({"analysis.duration": duration}), integrator="chang")
        planned = plan(system, settings)
        planned.fine_chunk = 1000
        tap = Alongside(planned, compare_stride(planned.layout, planned.compute_steps))
        result = planned.run(keep=False, tap=tap)
        assert "companion" in estimate(result, settings, companion=(planned, tap))
        kept.append(tap.nbytes)
        run_tap = RunTap(planned)
        planned.run(keep=False, tap=run_tap)
        whole.append(sum(a.nbytes for a in (run_tap.t, run_tap.d, run_tap.v, run_tap.f, run_tap.load, run_tap.levels)))
    assert kept[0] == kept[1] < 2_000_000
    assert whole[1] > 3.9 * whole[0]
