"""Shock response spectra in the terms of ISO 18431-4: positive and negative, primary and residual.

Each oscillator of natural frequency f (omega = 2 pi f) and damping ratio zeta (Q = 1 / (2 zeta))
is driven at its base by the acceleration a(t), sampled at a uniform dt and linear between
samples, and stepped by the exact recurrence of rbhyst.solve.spectra (Nigam and Jennings 1969),
with the same substeps and the same peaks between points (Hermite cubic through values and
slopes), so that the spectrum is exact to the piecewise-linear signal up to the peaks' O(h^4).
For every oscillator the absolute acceleration x'' + a = -(2 zeta omega x' + omega^2 x) is
followed with its sign:

- **primary**: its largest positive value and largest negative value (as a magnitude) over the
  record's samples, the time the excitation lasts;
- **residual**: the same over the free vibration that follows the record (the input ramping to
  zero over one step, then at rest) until every oscillator has passed both its positive and
  its negative peak: one damped period Td = 1 / (f sqrt(1 - zeta^2)) after the ramp (the free
  vibration is a damped sinusoid whose extrema of either sign come once a period and shrink);
- the relative displacement's largest |x| over both, and the pseudo-velocity 2 pi f max |x|.

Maximax = max of the four; positive = max(primary, residual) positive; likewise negative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from rbhyst.errors import InputError
from rbhyst.solve.spectra import _turning_value, step_coefficients, substep_counts

#: the columns of srs.csv, one row per damping and frequency
SRS_COLUMNS = ("q", "damping", "frequency_hz", "maximax_m_s2", "positive_m_s2", "negative_m_s2",
               "primary_m_s2", "residual_m_s2", "primary_positive_m_s2", "primary_negative_m_s2",
               "residual_positive_m_s2", "residual_negative_m_s2", "sd_m", "pv_m_s")


@dataclass(frozen=True)
class ShockSpectrum:
    """Peaks of shape (frequencies, dampings): absolute accelerations (m/s2 for input in m/s2)
    with their sign, primary (during the record) and residual (after it), and max |x| (m)."""

    frequencies_hz: np.ndarray
    dampings: np.ndarray
    dt: float
    samples: int
    primary_positive: np.ndarray
    primary_negative: np.ndarray
    residual_positive: np.ndarray
    residual_negative: np.ndarray
    sd: np.ndarray

    @property
    def primary(self) -> np.ndarray:
        return np.maximum(self.primary_positive, self.primary_negative)

    @property
    def residual(self) -> np.ndarray:
        return np.maximum(self.residual_positive, self.residual_negative)

    @property
    def positive(self) -> np.ndarray:
        return np.maximum(self.primary_positive, self.residual_positive)

    @property
    def negative(self) -> np.ndarray:
        return np.maximum(self.primary_negative, self.residual_negative)

    @property
    def maximax(self) -> np.ndarray:
        return np.maximum(self.primary, self.residual)

    @property
    def pv(self) -> np.ndarray:
        """Pseudo-velocity 2 pi f max |x| (m/s)."""
        return (2.0 * np.pi * self.frequencies_hz)[:, None] * self.sd

    @property
    def qs(self) -> np.ndarray:
        return 1.0 / (2.0 * self.dampings)

    def table(self) -> np.ndarray:
        """The rows of srs.csv (SRS_COLUMNS), damping by damping, frequency ascending."""
        rows = []
        for j, zeta in enumerate(self.dampings):
            n = len(self.frequencies_hz)
            q = math.inf if zeta == 0.0 else 1.0 / (2.0 * zeta)
            rows.append(np.column_stack([np.full(n, q), np.full(n, zeta), self.frequencies_hz] +
                                        [v[:, j] for v in (self.maximax, self.positive, self.negative, self.primary,
                                                           self.residual, self.primary_positive,
                                                           self.primary_negative, self.residual_positive,
                                                           self.residual_negative, self.sd, self.pv)]))
        return np.vstack(rows)


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


def residual_samples(frequencies, dampings, dt: float) -> int:
    """Samples of rest after the record: the ramp to zero, then one damped period of the lowest
    frequency (every oscillator has then passed a positive and a negative extremum of its free
    vibration, the largest of each sign: they shrink from one period to the next)."""
    td = 1.0 / (min(frequencies) * math.sqrt(1.0 - max(dampings) ** 2))
    return 1 + math.ceil(td / dt - 1e-9)


def shock_spectrum(acc, dt: float, frequencies_hz, dampings=(0.05,), points_per_period: int = 20) -> ShockSpectrum:
    """The shock response spectrum of ``acc`` (m/s2, uniform step ``dt``, starting at rest):
    primary over the samples, residual over the free vibration after them (see the module)."""
    a = np.ascontiguousarray(np.asarray(acc, dtype=float).ravel())
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    z = np.atleast_1d(np.asarray(dampings, dtype=float))
    problems = [f"frequencies: {v:g} Hz must be positive and finite" for v in f if not (math.isfinite(v) and v > 0)]
    problems += [f"dampings: {v:g} must be at least 0 and below 1" for v in z if not 0.0 <= v < 1.0]
    if not (math.isfinite(dt) and dt > 0):
        problems.append(f"dt: {dt!r} s must be positive")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        problems.append(f"acceleration: sample {bad[0] + 1} is {a[bad[0]]} (every sample must be a finite number)")
    if f.size == 0 or z.size == 0:
        problems.append("frequencies, dampings: at least one of each")
    if problems:
        raise InputError(problems)
    omega = np.repeat(2.0 * np.pi * f, len(z))
    zeta = np.tile(z, len(f))
    m = substep_counts(2.0 * np.pi / omega, dt, points_per_period)
    coef = np.empty((11, len(omega)))
    coef[:8] = step_coefficients(omega, zeta, dt / m).T
    coef[8] = 2.0 * zeta * omega
    coef[9] = omega * omega
    coef[10] = dt / m if points_per_period > 0 else 0.0
    rest = np.zeros(residual_samples(f, z, dt))
    peaks = np.zeros((5, len(omega)))
    if a.size >= 1:
        _shock_peaks(a, rest, coef, m, peaks)
    shape = (len(f), len(z))
    pp, pn, rp, rn, sd = (p.reshape(shape) for p in peaks)
    return ShockSpectrum(f.copy(), z.copy(), float(dt), int(a.size), pp, pn, rp, rn, sd)


@njit(cache=True, error_model="numpy")
def _shock_peaks(acc, rest, coef, m, peaks):
    """Every oscillator (column o of coef, m[o] substeps a step) from rest at acc[0] over acc, then
    over acc[-1] -> rest: peaks[0..3, o] the primary positive, primary negative, residual positive,
    residual negative absolute acceleration (magnitudes), peaks[4, o] max |x| over both."""
    for o in range(coef.shape[1]):
        a11, a12, a21, a22 = coef[0, o], coef[1, o], coef[2, o], coef[3, o]
        b11, b12, b21, b22 = coef[4, o], coef[5, o], coef[6, o], coef[7, o]
        cv, cx, hs = coef[8, o], coef[9, o], coef[10, o]
        mo = m[o]
        x = 0.0
        v = 0.0
        hi = 0.0
        lo = 0.0
        sd = 0.0
        a0 = acc[0]
        for part in range(2):
            src = acc if part == 0 else rest
            first = 1 if part == 0 else 0
            for i in range(first, src.shape[0]):
                a1 = src[i]
                da = (a1 - a0) / mo
                p0 = a0
                for k in range(1, mo + 1):
                    p1 = a0 + k * da if k < mo else a1
                    xn = (a11 * x + a12 * v) + (b11 * p0 + b12 * p1)
                    vn = (a21 * x + a22 * v) + (b21 * p0 + b22 * p1)
                    # the absolute acceleration is -(cv x' + cx x); its slope from x'' = -(a + y)
                    yo = -(cv * v + cx * x)
                    yn = -(cv * vn + cx * xn)
                    go = -(cx * v - cv * (p0 - yo))
                    gn = -(cx * vn - cv * (p1 - yn))
                    turn = _turning_value(yo, yn, go, gn, hs)
                    hi = max(hi, turn, yn)
                    lo = min(lo, turn, yn)
                    sd = max(sd, abs(_turning_value(x, xn, v, vn, hs)), abs(xn))
                    x = xn
                    v = vn
                    p0 = p1
                a0 = a1
            peaks[2 * part, o] = hi
            peaks[2 * part + 1, o] = 0.0 - lo  # (not -0.0 where it never went below)
            if part == 0:  # the residual's peaks start at the record's end, from its state there
                end = -(cv * v + cx * x)
                hi = max(end, 0.0)
                lo = min(end, 0.0)
        peaks[4, o] = sd
