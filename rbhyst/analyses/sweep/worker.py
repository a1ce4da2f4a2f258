"""What runs in a worker process (local or on a Dask cluster): a batch of cases in, one
plain dict per case out.

A worker keeps what it can between batches: the compiled kernels (numba loads them once
per process), each base deck parsed once, and each record file read once (the run keeps
the records it read, by path and modification time).
"""

from __future__ import annotations

import math
import os
import signal
import time
from typing import Any

import numpy as np

from rbhyst._version import __version__
from rbhyst.allocator import keep_freed_memory
from rbhyst.errors import AnalysisError, InputError

_bases: dict[str, Any] = {}
#: a local worker's place on its pool's board: (the board, the index of its pid there)
_slot: tuple[Any, int] | None = None


def init_local_worker(board=None, taken=None) -> None:
    """A local pool's worker: Ctrl-C reaches the whole process group, but only the sweep's own
    process decides what to do (it ends the workers); a worker whose parent dies ends too.

    ``board`` (shared memory, two integers per worker: its pid and the batch it runs) and
    ``taken`` (how many slots of it are taken) let the pool know which batch a worker that
    died was running."""
    global _slot
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # Linux: SIGTERM when the parent dies, so that no worker outlives a killed sweep
        import ctypes

        ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except Exception:  # pragma: no cover - not Linux
        pass
    if board is not None:
        with taken.get_lock():
            i = taken.value % (len(board) // 2)
            taken.value += 1
        _slot = (board, 2 * i)
        board[2 * i + 1] = 0
        board[2 * i] = os.getpid()


def run_tracked(batch: int, run, *args):
    """``run(*args)`` with ``batch`` on the board while it runs (see init_local_worker)."""
    if _slot is None:
        return run(*args)
    board, i = _slot
    board[i + 1] = batch
    try:
        return run(*args)
    finally:
        board[i + 1] = 0


def run_batch(base, cases: list[tuple[str, dict]], histories: bool = False) -> list[dict]:
    """Run ``cases`` ((key, deck values) each) on ``base`` (a cases.BaseDeck); one dict per case."""
    keep_freed_memory()  # (every batch: a Dask worker's process is not started by the sweep; two calls)
    deck = _bases.get(base.token)
    if deck is None:
        deck = _bases[base.token] = base.deck()
    return [run_case(deck, key, values, histories) for key, values in cases]


def run_case(base, key: str, values: dict, histories: bool = False) -> dict:
    """One case: status "ok" with the summary's peaks, energy and accuracy, or "failed" with
    the message the run (exit 3) or its input (a bad record) gave."""
    tic = time.perf_counter()
    out: dict[str, Any] = {"key": key, "rbhyst_version": __version__}
    try:
        result, late = run_to_rest(base.with_values(values), keep=histories)
    except (AnalysisError, InputError) as err:
        message = "; ".join(err.problems) if isinstance(err, InputError) else str(err)
        out.update(status="failed", message=message.replace("\n", " "), elapsed_s=time.perf_counter() - tic)
        return out
    except Exception as err:  # a bug, not the case: reported, and not kept, so a later run tries again
        out.update(status="failed", message=f"internal error: {err.__class__.__name__}: {err}".replace("\n", " "),
                   internal=True, elapsed_s=time.perf_counter() - tic)
        return out
    # the parts of summary.json a case keeps (not the whole: its modes alone are a tenth of a
    # short case's time around its computing)
    accuracy = result.accuracy
    out.update(
        status="ok",
        message="; ".join((result.warnings or []) + late).replace("\n", " "),
        peaks=_finite(result.extremes.peaks()),
        energy=_finite({k: v for k, v in result.energy_summary().items() if k != "warn_above"}),
        accuracy=_finite(without_timings(flat_numbers(accuracy))) if accuracy else {},
        stroke=_finite(stroke_utilizations(result.elements_summary())),
        # a case's computing: its time stepping and its error estimate
        wall_s=result.wall_s + ((accuracy or {}).get("wall_s") or 0.0),
        elapsed_s=time.perf_counter() - tic,
    )
    if histories and result.table is not None:
        out["history"] = {"columns": list(result.columns), "table": np.ascontiguousarray(result.table)}
    return out


def stroke_utilizations(elements: list[dict]) -> dict[str, float]:
    """{"e3": 0.8, ...}: each [[elements]] entry with a stroke, named by its first element's
    number in the CSV (its count deform alike), and the share of the stroke it used."""
    out, k = {}, 1
    for e in elements:
        if "stroke" in e:
            out[f"e{k}"] = e["stroke"]["utilization"]
        k += e["count"]
    return out


def run_to_rest(deck, keep: bool):
    """The case's run, and a line where its response may not have decayed: a deck that gives no
    analysis.duration runs through its motion and the free vibration after it
    (rbhyst.analyses.qualification.free_vibration: the first tail; the peaks include it)."""
    import dataclasses

    from rbhyst.analyses.qualification import free_vibration
    from rbhyst.results import analysis
    from rbhyst.solve.modes import initial_modes

    system, settings = analysis.scene(deck)
    end = system.excitation.duration
    if settings.duration is not None or end is None:
        return analysis.analyse(system, settings, keep=keep, spare_core=False), []
    tail = free_vibration.tail_s(initial_modes(system).frequencies_hz)
    result = analysis.analyse(system, dataclasses.replace(settings, duration=end + tail), keep=keep,
                              spare_core=False)  # (its siblings take the other cores)
    late = free_vibration.late_peaks(result.extremes.as_dict(), end + 0.5 * tail)
    if not late:
        return result, []
    column, t = late[0]
    return result, [f"the response may not have decayed {tail:.3g} s after the motion (a peak of {column} at "
                    f"{t:.4g} s, in the last half): its peaks are those of the time it ran"]


def run_deck(deck, keep: bool):
    """The deck's analysis as ``rbhyst.run`` makes it, keeping the rows only when asked: a sweep
    needs the reductions (peaks, energy, accuracy), and copying 40,000 rows it drops costs a
    third of a case."""
    from rbhyst.results import analysis

    return analysis.run_deck(deck, keep=keep, spare_core=False)  # (its siblings take the other cores)


def without_timings(d: dict) -> dict:
    """A case's numbers without what the machine's load decides (wall times): cases.csv stays
    the same whoever computes it, locally or on a cluster."""
    return {k: v for k, v in d.items() if not k.endswith("wall_s")}


def flat_numbers(data, prefix: str = "") -> dict[str, float]:
    """{"u1": {"rel": 1e-3}, "n": 3} -> {"u1_rel": 1e-3, "n": 3.0}: the numbers of a nested dict."""
    out: dict[str, float] = {}
    if isinstance(data, dict):
        for k, v in data.items():
            out.update(flat_numbers(v, f"{prefix}_{k}" if prefix else str(k)))
    elif isinstance(data, (int, float)) and not isinstance(data, bool) and prefix:
        out[prefix] = float(data)
    return out


def _finite(d: dict) -> dict:
    """JSON has no NaN or Inf: such a value is kept as None (an empty cell)."""
    return {k: (float(v) if v is not None and math.isfinite(v) else None) for k, v in d.items()
            if isinstance(v, (int, float)) and not isinstance(v, bool) or v is None}
