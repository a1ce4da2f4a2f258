"""The default periods of response spectra: a log-spaced grid from 0.01 s to 10 s."""

from __future__ import annotations

import math

import numpy as np

from rbhyst.errors import InputError


def default_periods(n: int = 100, t_min: float = 0.01, t_max: float = 10.0) -> np.ndarray:
    """``n`` periods (s) spaced evenly in logarithm from ``t_min`` to ``t_max``, both included."""
    if not (n >= 2 and 0.0 < t_min < t_max and math.isfinite(t_max)):
        raise InputError(f"default_periods: need n >= 2 and 0 < t_min < t_max, got {n}, {t_min}, {t_max}")
    return np.geomspace(t_min, t_max, n)
