"""Transmissibility by stepped sine: at each frequency and amplitude, a run under a sine
support acceleration until its response is steady, and T = the steady peak of |total
acceleration| / the input's amplitude, at G and at every point of interest.

**The input.** ``excitation`` is replaced by a sine along one direction whose amplitude
rises over RAMP_CYCLES cycles (signals.ramp_envelope, as a shaker ramps up): an abrupt
start leaves a free vibration that a lightly damped body keeps for many cycles (an
undamped one for ever); after the ramp it is down by about (|f - f0| T_ramp)^-3.

**Steady.** The run goes on in blocks: first RAMP_CYCLES + 2 WINDOW cycles, then twice as
many cycles after the ramp each time (a run starts from rest, so each block runs afresh:
at most twice the cost of the last). It is steady when, for every response, the peak over
the last WINDOW cycles and that over the WINDOW cycles before agree within SETTLE_TOL of
the larger (a response below NEGLIGIBLE of the input, such as the cross response of a
symmetric body, counts as settled). Windows, not single cycles, so that a response that
repeats every two or three cycles (subharmonics of a hysteretic scene) is steady too.
Past MAX_CYCLES after the ramp the last window is reported with a note.

**Steps.** dt = P / n with n = max(STEPS_PER_PERIOD, ceil(P / the deck's dt)) steps a
period P: never coarser than the deck's dt, and whole cycles on the grid. Peaks between
samples are found by a parabola through the largest sample and its neighbours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from rbhyst.errors import InputError

RAMP_CYCLES = 20
WINDOW = 4
SETTLE_TOL = 0.005
NEGLIGIBLE = 1e-6
MAX_CYCLES = 128
STEPS_PER_PERIOD = 100
DIRECTIONS = ("x1", "x2")
#: a deck in space: the support's sine along x1, x2 or x3 (vertical), T along all three
SPACE_DIRECTIONS = ("x1", "x2", "x3")


def directions(deck) -> tuple[str, ...]:
    """The directions of the deck's body: x1, x2 in the plane; x1, x2, x3 in space."""
    return SPACE_DIRECTIONS if deck.body is not None and deck.body.dimensions == 3 else DIRECTIONS


@dataclass(frozen=True)
class SteadyState:
    """One frequency at one amplitude."""

    frequency_hz: float
    amplitude_m_s2: float
    T: dict[str, float]  # "T_<location>_<direction>" -> steady peak |at| / amplitude
    dt_s: float
    cycles: int  # after the ramp, in the last block
    settled: bool
    change: float  # largest relative change between the last two windows
    wall_s: float


@dataclass
class Transmissibility:
    direction: str
    columns: list[str]  # T_G_x1, T_G_x2 (T_G_x3 in space), T_<point>_x1, ...
    runs: list[SteadyState] = field(default_factory=list)

    @property
    def notes(self) -> list[str]:
        return [f"{r.frequency_hz:g} Hz, {r.amplitude_m_s2:g} m/s2: not steady after {r.cycles} cycles "
                f"(the peaks of the last two {WINDOW}-cycle windows differ by {r.change:.2%}): "
                f"T is that of the last {WINDOW} cycles" for r in self.runs if not r.settled]

    def table(self) -> np.ndarray:
        """Rows frequency_hz, amplitude_m_s2, then the T columns; by amplitude, then frequency."""
        runs = sorted(self.runs, key=lambda r: (r.amplitude_m_s2, r.frequency_hz))
        return np.array([[r.frequency_hz, r.amplitude_m_s2, *(r.T[c] for c in self.columns)] for r in runs])

    def summary(self) -> dict:
        return {"direction": self.direction, "columns": ["frequency_hz", "amplitude_m_s2", *self.columns],
                "method": {"ramp_cycles": RAMP_CYCLES, "window_cycles": WINDOW, "settle_tolerance": SETTLE_TOL,
                           "negligible_fraction_of_input": NEGLIGIBLE, "max_cycles_after_ramp": MAX_CYCLES,
                           "min_steps_per_period": STEPS_PER_PERIOD},
                "runs": [{"frequency_hz": r.frequency_hz, "amplitude_m_s2": r.amplitude_m_s2, "dt_s": r.dt_s,
                          "cycles_after_ramp": r.cycles, "settled": r.settled, "last_change": r.change,
                          "wall_s": r.wall_s, **r.T}
                         for r in sorted(self.runs, key=lambda r: (r.amplitude_m_s2, r.frequency_hz))],
                "notes": self.notes}


def t_columns(deck) -> list[str]:
    names = ["G", *(p.name for p in deck.output.points or ())]
    return [f"T_{n}_{d}" for n in names for d in directions(deck)]


def request_problems(direction: str, amplitudes, frequencies, axes: tuple[str, ...] = DIRECTIONS) -> list[str]:
    """One line per problem with the sweep asked for (amplitudes in any one unit); ``axes``: the
    deck's directions (:func:`directions`)."""
    problems = []
    if direction not in axes:
        said = "x1 or x2" if axes == DIRECTIONS else "x1, x2 or x3"
        tail = " (x3, the vertical, for a deck in space)" if direction == "x3" and axes == DIRECTIONS else ""
        problems.append(f"--direction: {direction!r}: {said}{tail}")
    if not amplitudes:
        problems.append("--amplitude: at least one amplitude")
    problems += [f"--amplitude: {a:g} must be positive" for a in amplitudes if not (a > 0 and math.isfinite(a))]
    if not frequencies:
        problems.append("frequencies: at least one (--frequencies, or --from, --to and --count)")
    problems += [f"frequencies: {f:g} Hz must be positive" for f in frequencies if not (f > 0 and math.isfinite(f))]
    if len(set(frequencies)) != len(frequencies):
        problems.append("frequencies: each frequency once")
    if len(set(amplitudes)) != len(amplitudes):
        problems.append("--amplitude: each amplitude once")
    return problems


def sine_deck(deck, direction: str, amplitude: float, frequency: float, cycles: int):
    """The deck under a ramped sine of ``cycles`` cycles after the ramp, on the grid it needs."""
    period = 1.0 / frequency
    n = max(STEPS_PER_PERIOD, math.ceil(period / deck.analysis.dt - 1e-9))
    dt = period / n
    output = {"plots": False}
    if deck.output.points:
        output["points"] = [p.model_dump() for p in deck.output.points]
    return deck.with_values({
        "excitation": {"support": {direction: {"type": "sine", "amplitude": amplitude, "frequency_hz": frequency,
                                               "units": "m/s2", "ramp_cycles": float(RAMP_CYCLES)}}},
        "analysis.dt": dt, "analysis.duration": (RAMP_CYCLES + cycles) * period,
        "output": output,
    }), n


def window_peaks(y: np.ndarray, n: int, windows: int) -> np.ndarray:
    """max |y| over each of the last ``windows`` windows of WINDOW cycles of n samples (each
    window's ends included), refined by a parabola through the largest sample."""
    out = np.empty(windows)
    end = len(y) - 1
    for w in range(windows):
        hi = end - w * WINDOW * n
        seg = np.abs(y[hi - WINDOW * n:hi + 1])
        i = int(np.argmax(seg))
        peak = seg[i]
        if 0 < i < len(seg) - 1:
            a, b, c = seg[i - 1], seg[i], seg[i + 1]
            curv = a - 2.0 * b + c
            if curv < 0.0:
                peak = b - 0.125 * (a - c) ** 2 / curv
        out[windows - 1 - w] = peak
    return out


def steady_state(deck, direction: str, amplitude: float, frequency: float) -> SteadyState:
    """Run blocks of growing length until every response's window peaks settle (or the cap)."""
    import time

    from rbhyst.results.analysis import run_deck

    columns = t_columns(deck)
    sources = {c: ("" if c.startswith("T_G_") else c[2:-3] + "_") + f"at{c[-1]}_m_s2" for c in columns}
    cycles = 2 * WINDOW
    tic = time.perf_counter()
    while True:
        d, n = sine_deck(deck, direction, amplitude, frequency, cycles)
        res = run_deck(d, estimate=False)
        peaks = {c: window_peaks(res.column(src), n, 2) for c, src in sources.items()}
        change = 0.0
        for prev, last in peaks.values():
            scale = max(prev, last, NEGLIGIBLE * amplitude)
            change = max(change, abs(last - prev) / scale)
        settled = bool(change <= SETTLE_TOL)
        if settled or cycles >= MAX_CYCLES:
            break
        cycles *= 2
    return SteadyState(frequency_hz=frequency, amplitude_m_s2=amplitude,
                       T={c: float(p[-1] / amplitude) for c, p in peaks.items()}, dt_s=d.analysis.dt,
                       cycles=cycles, settled=settled, change=float(change), wall_s=time.perf_counter() - tic)


def _task(args):
    """One steady state; the deck travels as its data (pydantic's generic models do not pickle)."""
    data, source, direction, amplitude, frequency = args
    from rbhyst.model.deck import parse_deck

    deck = parse_deck(data)
    deck._source = source
    return steady_state(deck, direction, amplitude, frequency)


def _quiet_worker() -> None:
    """Ctrl-C reaches the whole process group: the parent stops the workers, which say nothing."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


#: below this many runs left a pool costs more than it saves
POOL_FROM = 4


def stepped_sine(deck, direction: str, amplitudes, frequencies, workers: int = 1,
                 progress: Callable[[str, int, int], None] | None = None) -> Transmissibility:
    """Every frequency at every amplitude (m/s2), in ``workers`` processes (1: in this one).

    The first run is made here: a mistake in the deck is reported before any worker starts,
    and the compiled kernels are loaded once, for the workers forked after it to share.
    """
    import sys

    from rbhyst.model.deck import check_runnable

    check_runnable(deck)
    amplitudes, frequencies = [float(a) for a in amplitudes], [float(f) for f in frequencies]
    problems = request_problems(direction, amplitudes, frequencies, directions(deck))
    if problems:
        raise InputError(problems)
    data = deck.model_dump(mode="python", exclude_unset=True)
    tasks = [(data, deck.source, direction, a, f) for a in amplitudes for f in frequencies]
    result = Transmissibility(direction, t_columns(deck))

    def done(r: SteadyState) -> None:
        result.runs.append(r)
        if progress:
            progress(f"{r.frequency_hz:.4g} Hz, {r.amplitude_m_s2:.4g} m/s2", len(result.runs), len(tasks))

    if progress:
        progress("first run", 0, len(tasks))
    done(_task(tasks[0]))
    rest = tasks[1:]
    if workers > 1 and len(rest) >= POOL_FROM:
        import multiprocessing

        # fork shares the loaded kernels (spawn would load them again in every worker)
        ctx = multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")
        pool = ctx.Pool(processes=workers, initializer=_quiet_worker)
        try:
            for r in pool.imap_unordered(_task, rest):
                done(r)
        except BaseException:
            pool.terminate()
            raise
        finally:
            pool.close()
            pool.join()
    else:
        for t in rest:
            done(_task(t))
    return result


def frequency_list(frequencies, f_from, f_to, count) -> list[float]:
    """--frequencies, or --count frequencies log-spaced from --from to --to (one or the other)."""
    ranged = (f_from, f_to, count)
    if frequencies is not None:
        if any(v is not None for v in ranged):
            raise InputError("--frequencies: give either a list or --from, --to and --count, not both")
        return list(frequencies)
    if any(v is None for v in ranged):
        missing = [n for n, v in zip(("--from", "--to", "--count"), ranged) if v is None]
        raise InputError(f"frequencies: --frequencies, or --from, --to and --count ({', '.join(missing)} "
                         "missing)")
    problems = []
    if not (f_from > 0 and math.isfinite(f_from)):
        problems.append(f"--from: {f_from:g} Hz must be positive")
    if not (f_to > f_from):
        problems.append(f"--to: {f_to:g} Hz must be above --from ({f_from:g} Hz)")
    if count < 2:
        problems.append(f"--count: {count} must be at least 2")
    if problems:
        raise InputError(problems)
    return [float(f) for f in np.geomspace(f_from, f_to, count)]


def write_csv(result: Transmissibility, path) -> None:
    from pathlib import Path

    header = ",".join(["frequency_hz", "amplitude_m_s2", *result.columns])
    lines = [header] + [",".join(f"{v:.10g}" for v in row) for row in result.table()]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_json(result: Transmissibility, path) -> None:
    import json
    from pathlib import Path

    from rbhyst._version import __version__

    Path(path).write_text(json.dumps({"rbhyst_version": __version__, **result.summary()}, indent=2) + "\n")
