"""The free vibration after a motion: how long a run goes on once its support is at rest, and
whether its response has decayed by then.

A body on its mounts keeps ringing after the table stops, and a peak of that free vibration
counts as much as one during the motion (a test lab records until the table's and the
specimen's motion have died out). A qualification run therefore continues after its motion
for a tail of ``max(TAIL_MIN_S, TAIL_PERIODS / f1)``, f1 the lowest natural frequency of the
initial system (rbhyst.solve.modes). The response counts as decayed when the second half of
that tail raises no peak of the response (every output column but the ground's and the
accumulating energies) by more than ``analysis.warn_error`` of it: going on would not change
the figures beyond the accuracy asked of them. Where it does, the tail is doubled and the run
made again, up to TAIL_TRIES runs; one that has still not decayed says so in a note, its peaks
those of the time it ran. A sweep's case (rbhyst.analyses.sweep.worker) runs the same first tail
and keeps no rows: where a peak lies in its second half, its message says the response may not
have decayed. (A mount whose loading and unloading curves differ ratchets: the
cabinet on the seed's wire rope sets settles by some 0.3 % of its vertical peak each time its
free vibration doubles, which this rule lets pass.)
"""

from __future__ import annotations

import math

import numpy as np

#: the tail after a motion: at least this long (s) ...
TAIL_MIN_S = 2.0
#: ... and this many periods of the lowest mode
TAIL_PERIODS = 10.0
#: a run whose response has not decayed is made again with a tail this many times longer ...
TAIL_GROWTH = 2.0
#: ... at most this many times in all
TAIL_TRIES = 3
#: the rule as qualification.json states it
RULE = (f"each run goes on after its motion for max({TAIL_MIN_S:g} s, {TAIL_PERIODS:g} periods of the initial "
        "system's lowest mode); the response has decayed when the second half of that free vibration raises no "
        f"peak by more than analysis.warn_error, else the tail is multiplied by {TAIL_GROWTH:g} and the run made "
        f"again (at most {TAIL_TRIES} runs); the peaks include the free vibration")
#: the columns a run's decay is judged on are its response's: not the ground's input, nor the
#: energies that accumulate (their largest value is always their last)
_NOT_RESPONSE = ("ag", "E_input", "E_hysteretic", "E_error", "E_damping")
#: a column whose peak is below this share of the largest peak in its unit is at rest (rounding)
_AT_REST = 1e-6


def tail_s(frequencies_hz) -> float:
    """The first tail after a motion: TAIL_PERIODS periods of the lowest (non-zero) frequency,
    at least TAIL_MIN_S."""
    f = [x for x in frequencies_hz if x > 0.0 and math.isfinite(x)]
    return max(TAIL_MIN_S, TAIL_PERIODS / min(f)) if f else TAIL_MIN_S


def late_peaks(extremes: dict, after_s: float) -> list[tuple[str, float]]:
    """The response columns (summary.json's ``extremes``) whose peak |value| lies after
    ``after_s``, with its time (columns at rest left out): none means the second half of a
    tail raised no peak at all, the rule met without the rows; some means it may have."""
    peaks = {}
    for column, e in extremes.items():
        if "max" in e:
            hi, lo = abs(e["max"]), abs(e["min"])
            peaks[column] = (hi, e["time_of_max_s"]) if hi >= lo else (lo, e["time_of_min_s"])
    moving = _moving({c: p for c, (p, _) in peaks.items()})
    return [(c, peaks[c][1]) for c in moving if peaks[c][1] > after_s]


def grown(time: np.ndarray, columns: dict[str, np.ndarray], split_s: float,
          tolerance: float) -> list[tuple[str, float]]:
    """The response columns whose peak |value| after ``split_s`` exceeds the one before by more
    than ``tolerance`` of it, with their growth; columns at rest left out."""
    before = time <= split_s
    whole = {c: float(np.max(np.abs(x), initial=0.0)) for c, x in columns.items()}
    out = []
    for c in _moving(whole):
        first = float(np.max(np.abs(columns[c][before]), initial=0.0))
        if whole[c] > first * (1.0 + tolerance):
            out.append((c, whole[c] / first - 1.0 if first > 0.0 else math.inf))
    return out


def _moving(peaks: dict[str, float]) -> list[str]:
    """The response columns of ``peaks`` (column -> peak |value|) not at rest: not the ground's
    nor an accumulating energy, and with a peak above _AT_REST of the largest in their unit."""
    response = {c: p for c, p in peaks.items() if not c.startswith(_NOT_RESPONSE)}
    largest: dict[str, float] = {}
    for c, p in response.items():
        largest[_unit(c)] = max(largest.get(_unit(c), 0.0), p)
    return [c for c, p in response.items() if p > _AT_REST * largest[_unit(c)]]


#: the units' suffixes of the output columns, longest first
_UNITS = ("_m_s2", "_rad_s2", "_m_s", "_rad_s", "_rad", "_Nm", "_m", "_N", "_J")


def _unit(column: str) -> str:
    return next((u for u in _UNITS if column.endswith(u)), "")
