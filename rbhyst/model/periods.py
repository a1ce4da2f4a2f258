"""The default oscillators of spectra: periods log-spaced from 0.01 s to 10 s (response spectra),
frequencies at a fraction of an octave (shock response spectra)."""

from __future__ import annotations

import math

import numpy as np

from rbhyst.errors import InputError


def default_periods(n: int = 100, t_min: float = 0.01, t_max: float = 10.0) -> np.ndarray:
    """``n`` periods (s) spaced evenly in logarithm from ``t_min`` to ``t_max``, both included."""
    if not (n >= 2 and 0.0 < t_min < t_max and math.isfinite(t_max)):
        raise InputError(f"default_periods: need n >= 2 and 0 < t_min < t_max, got {n}, {t_min}, {t_max}")
    return np.geomspace(t_min, t_max, n)


#: the highest default frequency of a shock spectrum, Hz, and the least samples a period
SRS_TOP_HZ, SRS_SAMPLES_PER_PERIOD = 10_000.0, 10


def srs_range(dt: float) -> tuple[float, float]:
    """A shock spectrum's default range for samples ``dt`` apart: 1 Hz to the lesser of 10 kHz and
    a tenth of the sample rate (ten samples a period of the highest: above it the signal's content
    is shaped by its sampling), at least 2 Hz."""
    return 1.0, max(min(SRS_TOP_HZ, 1.0 / (SRS_SAMPLES_PER_PERIOD * dt)), 2.0)


def octave_frequencies(lo: float, hi: float, per_octave: int = 12) -> np.ndarray:
    """lo, lo 2^(1/n), ... up to hi (hi itself last when the octaves do not land on it)."""
    problems = []
    if not (math.isfinite(lo) and lo > 0 and math.isfinite(hi) and hi > lo):
        problems.append(f"--frequencies: {lo:g}..{hi:g} Hz: two positive frequencies, the lower first")
    if not (isinstance(per_octave, (int, np.integer)) and per_octave >= 1):
        problems.append(f"--per-octave: {per_octave!r}: a whole number, 1 or more")
    if problems:
        raise InputError(problems)
    n = math.floor(per_octave * math.log2(hi / lo) + 1e-9)
    f = lo * 2.0 ** (np.arange(n + 1) / per_octave)
    return f if f[-1] >= hi * (1.0 - 1e-9) else np.append(f, hi)
