"""The frequency a body actually rang at, from its response: summary.json's ``rang``, beside the
modes (which are those of one stiffness, while a hysteretic mount's depends on how far it moves).

Over the free part of the run (after the last excitation has ended: a pulse, a sine with an end,
a record), each coordinate's displacement is cut at its reversals (a turn back by more than
BAND of its range there, so that rounding and small wiggles near rest are not cycles), each
reversal's time refined by the parabola through its three samples. The frequency is the number
of half cycles over the time between the first and the last reversal, / 2; the first and the last
full cycle's own frequency and the amplitudes (half the swing) of the first and the last half
cycle show how it changed as the motion decayed. The response is the one the run's error
estimate compares (every compute step of a run of ordinary length).
"""

from __future__ import annotations

import math

import numpy as np

#: a reversal is a turn back by more than this fraction of the coordinate's range over the free part
BAND = 0.01
#: a coordinate whose range (a rotation's times its radius of gyration) is below this fraction of the
#: largest coordinate's moved by rounding alone: at rest
ROUNDING = 1e-9
#: fewer samples than this per half cycle cannot place a reversal
MIN_SAMPLES = 6
METHOD = ("reversals of the displacement over the free part (after the excitation ends): half cycles "
          "/ (2 x the time from the first to the last)")


def reversals(x: np.ndarray, band: float) -> np.ndarray:
    """Indices of the alternating extrema of ``x`` whose swings exceed ``band`` (the ends of
    ``x`` are not reversals)."""
    dx = np.diff(x)
    turns = np.flatnonzero(np.sign(dx[1:]) * np.sign(dx[:-1]) < 0) + 1  # (candidates: local extrema)
    kept: list[int] = []
    lo = hi = 0  # before the first swing: the lowest and highest candidate so far
    ref, direction = 0, 0  # after it: the running extreme since the last reversal, and its way
    for i in np.concatenate([turns, [len(x) - 1]]):
        if direction == 0:
            lo = i if x[i] < x[lo] else lo
            hi = i if x[i] > x[hi] else hi
            if x[i] - x[lo] > band:
                kept += [lo] if lo > 0 else []
                direction, ref = 1, i
            elif x[hi] - x[i] > band:
                kept += [hi] if hi > 0 else []
                direction, ref = -1, i
        elif (x[i] - x[ref]) * direction >= 0:  # further the same way: a new running extreme
            ref = i
        elif abs(x[i] - x[ref]) > band:  # turned back past the band: ref was a reversal
            kept.append(ref)
            direction, ref = -direction, i
    return np.array(kept, dtype=int)


def _refined(t: np.ndarray, x: np.ndarray, i: int) -> float:
    """The time of the extremum at sample i, from the parabola through samples i-1, i, i+1."""
    if i <= 0 or i >= len(x) - 1:
        return float(t[i])
    a, b, c = x[i - 1], x[i], x[i + 1]
    den = a - 2.0 * b + c
    if den == 0.0:
        return float(t[i])
    return float(t[i] + 0.5 * (a - c) / den * 0.5 * (t[i + 1] - t[i - 1]))


def coordinate_ringing(t: np.ndarray, x: np.ndarray) -> dict:
    """The frequency one coordinate rang at over (t, x), or why none is given."""
    span = float(np.ptp(x)) if len(x) else 0.0
    if span == 0.0 or not math.isfinite(span):
        return {"frequency_hz": None, "why": "at rest over the free part"}
    rev = reversals(x, BAND * span)
    if len(rev) < 3:
        return {"frequency_hz": None, "why": f"{max(len(rev) - 1, 0)} half cycle(s) in the free part: not one whole cycle"}
    if np.min(np.diff(rev)) < MIN_SAMPLES:
        return {"frequency_hz": None, "why": "fewer than 6 samples per half cycle: too coarse to count"}
    times = np.array([_refined(t, x, int(i)) for i in rev])
    halves = len(rev) - 1
    amp = 0.5 * np.abs(np.diff(x[rev]))
    return {"frequency_hz": halves / (2.0 * float(times[-1] - times[0])), "half_cycles": halves,
            "first_cycle_hz": 1.0 / float(times[2] - times[0]), "last_cycle_hz": 1.0 / float(times[-1] - times[-3]),
            "amplitude_first": float(amp[0]), "amplitude_last": float(amp[-1]),
            "from_s": float(times[0]), "to_s": float(times[-1])}


def ringing(t: np.ndarray, d: np.ndarray, names, free_from: float | None, lengths=None) -> dict:
    """summary.json's ``rang``: ``d`` (n, k) the coordinates ``names`` at times ``t``; the free part
    from ``free_from`` s (None: the excitation never ends); ``lengths`` (k,) what makes each
    coordinate a length (1 for a translation, the radius of gyration for a rotation), for ROUNDING."""
    out = {"method": METHOD, "free_from_s": free_from}
    if free_from is None:
        return {**out, "coordinates": None, "why": "the excitation does not end (a sine without an end)"}
    free = t >= free_from
    if np.count_nonzero(free) < 3 * MIN_SAMPLES:
        return {**out, "coordinates": None, "why": "no free vibration: the excitation lasts to the end of the run"}
    x = d[free]
    span = np.ptp(x, axis=0) * (np.ones(x.shape[1]) if lengths is None else np.asarray(lengths, dtype=float))
    top = float(np.max(span))
    coords = {}
    for j, name in enumerate(names):
        coords[name] = ({"frequency_hz": None, "why": "at rest over the free part"} if span[j] <= ROUNDING * top
                        else coordinate_ringing(t[free], x[:, j]))
    return {**out, "coordinates": coords}
