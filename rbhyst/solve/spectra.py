"""Response spectra of linear oscillators under an acceleration history, whole or streamed.

Each oscillator of natural period T (omega = 2 pi / T) and damping ratio zeta is driven at
its base by the acceleration a(t), sampled at a uniform dt and taken as linear between
samples:

    x'' + 2 zeta omega x' + omega^2 x = -a(t)

x is the displacement relative to the base and x'' + a = -(2 zeta omega x' + omega^2 x) the
absolute acceleration. For such an input the step from one sample to the next is an exact
linear recurrence (Nigam, N. C. and Jennings, P. C., 1969, Calculation of response spectra
from strong-motion earthquake records, Bull. Seismol. Soc. Am. 59(2), 909-922):

    (x, x')_{i+1} = A (x, x')_i + B (a_i, a_{i+1})

whose coefficients depend only on omega, zeta and the step, so the response has no
truncation error, only rounding. What is reported is the largest |x| (``sd``) and the
largest |x'' + a| (``sa``, the maximax shock or in-structure spectrum) over the points at
which the response is evaluated, and ``psa`` = omega^2 sd.

**Peaks between points.** The recurrence is exact at any step, but a maximum taken over
points T / 2 or more apart can miss the peak altogether. Every oscillator is therefore
evaluated at least ``points_per_period`` times per period: where T < points_per_period x dt,
each step is split into m = ceil(points_per_period dt / T) equal substeps (the input is linear
within the step, so the substeps are exact too). Between two points x and the absolute
acceleration are smooth, and their values and slopes at both are known exactly; where a slope
changes sign the peak is taken on the cubic through them (Hermite interpolation): a sinusoidal
response evaluated 20 times a period peaks within 3e-5 of its amplitude (the points alone can
miss it by 1 - cos(pi / 20) = 1.2 %), and under white noise at the sampling rate the peaks of a
period of 20 dt are within 2e-3 of the continuous response's (the points alone: 19 %, measured
in tests/test_spectra.py). Below T = points_per_period x dt the cost of an oscillator grows as
dt / T. ``points_per_period=0`` takes the maxima over the record's samples only, as most codes
do. The substeps resolve the response to the piecewise-linear input; they do not restore the
content above the record's Nyquist frequency that linear interpolation leaves out (for that,
resample the record with a band-limited interpolation first; Boore, D. M. and Goulet, C. A.,
2014, Bull. Earthquake Eng. 12, 203-216).

Units: acceleration in m/s^2 gives sd in m and sa, psa in m/s^2 (everything is linear in
the input, so any consistent unit works).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from rbhyst.errors import InputError
from rbhyst.model.periods import default_periods  # noqa: F401  (part of this module's API)

#: omega h below this: coefficients from the series of the exponential; the closed form
#: loses digits to cancellation there (terms of size 1/(omega h)^3 that nearly cancel)
_SERIES_BELOW = 1.0
_SERIES_TERMS = 32  # |M| <= 3 for omega h <= 1: the 32nd term is below 1e-18

# coefficient columns: x+ = A11 x + A12 v + B11 a + B12 a+, v+ = A21 x + A22 v + B21 a + B22 a+;
# then 2 zeta omega and omega^2 for the absolute acceleration, and the substep
_N_COEF = 11


@dataclass(frozen=True)
class Spectrum:
    """Peak responses, each of shape (periods, dampings, signals).

    sd: max |x| (m for input in m/s^2); sa: max |x'' + a| (m/s^2); psa = omega^2 sd.
    ``samples`` input samples were seen at spacing ``dt``; with fewer than two every
    peak is 0 (the oscillators start at rest, where x'' + a = 0).
    """

    periods: np.ndarray
    dampings: np.ndarray
    dt: float
    samples: int
    sd: np.ndarray
    sa: np.ndarray

    @property
    def psa(self) -> np.ndarray:
        omega = 2.0 * np.pi / self.periods
        return (omega * omega)[:, None, None] * self.sd


def step_coefficients(omega, damping, h) -> np.ndarray:
    """The exact recurrence over a step h for input linear in the step (Nigam and Jennings 1969).

    Returns an array of shape broadcast(omega, damping, h) + (8,): A11, A12, A21, A22, B11,
    B12, B21, B22 with x+ = A11 x + A12 x' + B11 a + B12 a+ and x'+ = A21 x + A22 x' + B21 a
    + B22 a+ for x'' + 2 zeta omega x' + omega^2 x = -a. Needs 0 <= damping < 1.

    For omega h >= 1 Nigam and Jennings' closed form. Below, that form subtracts terms up
    to 1/(omega h)^3 times larger than the result (7 digits lost at omega h = 1e-3, a 6 s
    oscillator at dt = 1 ms), so the same exponential is summed as its series in the scaled
    variables (x, h x', h^2 a, h^2 (a+ - a)), whose terms do not cancel. Both agree with a
    50-digit evaluation to a few roundings (tests/test_spectra.py).
    """
    w, z, h = np.broadcast_arrays(np.asarray(omega, float), np.asarray(damping, float), np.asarray(h, float))
    out = np.empty(w.shape + (8,))
    wh = w * h
    near = wh < _SERIES_BELOW
    if np.any(~near):
        out[~near] = _closed_form(w[~near], z[~near], h[~near])
    if np.any(near):
        out[near] = _series(wh[near], z[near], h[near])
    return out


def _closed_form(w, z, h):
    zs = np.sqrt(1.0 - z * z)
    wd = w * zs
    e = np.exp(-z * w * h)
    s = np.sin(wd * h)
    c = np.cos(wd * h)
    t2 = (2.0 * z * z - 1.0) / (w * w * h)
    t3 = 2.0 * z / (w * w * w * h)
    iw2 = 1.0 / (w * w)
    cz = c - z / zs * s
    a11 = e * (z / zs * s + c)
    a12 = e * s / wd
    a21 = -w / zs * e * s
    a22 = e * cz
    b11 = e * ((t2 + z / w) * s / wd + (t3 + iw2) * c) - t3
    b12 = -e * (t2 * s / wd + t3 * c) - iw2 + t3
    b21 = e * ((t2 + z / w) * cz - (t3 + iw2) * (wd * s + z * w * c)) + iw2 / h
    b22 = -e * (t2 * cz - t3 * (wd * s + z * w * c)) - iw2 / h
    return np.stack([a11, a12, a21, a22, b11, b12, b21, b22], axis=-1)


def _series(wh, z, h):
    # d/ds (X, V, F, G) = M (X, V, F, G) in s = t/h, X = x, V = h x', F = -h^2 a(t), G = dF/ds
    n = wh.shape[0]
    m = np.zeros((n, 4, 4))
    m[:, 0, 1] = 1.0
    m[:, 1, 0] = -wh * wh
    m[:, 1, 1] = -2.0 * z * wh
    m[:, 1, 2] = 1.0
    m[:, 2, 3] = 1.0
    e = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    term = e.copy()
    for k in range(1, _SERIES_TERMS):
        term = term @ m / k
        e += term
    hh = h * h
    # X+ = E00 X + E01 V + E02 F + E03 (F+ - F), F = -h^2 a
    return np.stack([e[:, 0, 0], e[:, 0, 1] * h, e[:, 1, 0] / h, e[:, 1, 1],
                     -hh * (e[:, 0, 2] - e[:, 0, 3]), -hh * e[:, 0, 3],
                     -h * (e[:, 1, 2] - e[:, 1, 3]), -h * e[:, 1, 3]], axis=-1)


def substep_counts(periods, dt: float, points_per_period: int) -> np.ndarray:
    """Substeps per sample step for each period: ceil(points_per_period dt / T), at least 1."""
    periods = np.asarray(periods, float)
    if points_per_period <= 0:
        return np.ones(periods.shape, dtype=np.int64)
    # the 1e-9: an exact ratio (T = 0.2 s at 20 x 10 ms) must not cost a substep more for a rounding
    return np.maximum(1, np.ceil(points_per_period * dt / periods - 1e-9)).astype(np.int64)


class SpectrumAccumulator:
    """Running peaks of every oscillator, fed the acceleration chunk by chunk.

    ``update(chunk)`` takes an (n, n_signals) array of the next n samples (a 1-D array
    when n_signals is 1); ``result()`` gives the :class:`Spectrum` of all samples so far.
    The oscillators start at rest at the first sample; each carries its state (x, x') and
    the last input sample across chunks, so any split of a history gives results
    bit-identical to feeding it whole, and only the state (a few arrays of periods x
    dampings x signals) is ever held.
    """

    def __init__(self, periods, dampings, n_signals: int, dt: float, points_per_period: int = 20):
        """``dt``: the step between samples (a chunk may say another, see :meth:`update`)."""
        self.periods, self.dampings = _checked_oscillators(periods, dampings)
        problems = []
        if not (isinstance(dt, (int, float, np.floating, np.integer)) and math.isfinite(dt) and dt > 0):
            problems.append(f"dt: {dt!r} s must be a positive number")
        if not (isinstance(n_signals, (int, np.integer)) and n_signals >= 1):
            problems.append(f"n_signals: {n_signals!r} must be a whole number of at least 1")
        if not (isinstance(points_per_period, (int, np.integer)) and points_per_period >= 0):
            problems.append(f"points_per_period: {points_per_period!r} must be a whole number, 0 or more")
        if problems:
            raise InputError(problems)
        self.dt = float(dt)
        self.n_signals = int(n_signals)
        self.points_per_period = int(points_per_period)
        # oscillator o = period j, damping k at o = j * n_dampings + k, stored by period from the
        # longest: whatever the step, substep counts then never decrease along them, and each
        # count is one contiguous group for the kernel
        omega = np.repeat(2.0 * np.pi / self.periods, len(self.dampings))
        zeta = np.tile(self.dampings, len(self.periods))
        period = np.repeat(self.periods, len(self.dampings))
        self._order = np.argsort(-period, kind="stable")
        self._period, self._omega, self._zeta = period[self._order], omega[self._order], zeta[self._order]
        self._steps: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        n = len(self._omega)
        self._x = np.zeros((self.n_signals, n))
        self._v = np.zeros((self.n_signals, n))
        self._sd = np.zeros((self.n_signals, n))
        self._up = np.zeros((self.n_signals, n))
        self._down = np.zeros((self.n_signals, n))
        self._last = np.zeros(self.n_signals)
        self.samples = 0

    def _step(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(coefficients, groups) of every oscillator for samples h apart, computed once per h."""
        if h not in self._steps:
            m = substep_counts(self._period, h, self.points_per_period)
            edges = np.flatnonzero(np.diff(m)) + 1
            first = np.concatenate([[0], edges])
            end = np.concatenate([edges, [len(m)]])
            groups = np.ascontiguousarray(np.stack([first, end, m[first]], axis=1), dtype=np.int64)
            coef = np.empty((_N_COEF, len(m)))
            coef[:8] = step_coefficients(self._omega, self._zeta, h / m).T
            coef[8] = 2.0 * self._zeta * self._omega
            coef[9] = self._omega * self._omega
            coef[10] = h / m if self.points_per_period > 0 else 0.0  # 0: the points alone
            self._steps[h] = (coef, groups)
        return self._steps[h]

    def update(self, chunk, h: float | None = None) -> None:
        """Advance every oscillator over the next samples (SI: m/s^2), ``h`` apart (default the
        accumulator's dt; the first sample of a chunk follows the last one before it by ``h``)."""
        a = np.asarray(chunk, dtype=float)
        if a.ndim == 1 and self.n_signals == 1:
            a = a[:, None]
        if a.ndim != 2 or a.shape[1] != self.n_signals:
            raise InputError(f"acceleration: a chunk of shape {a.shape} where (n, {self.n_signals}) "
                             f"was expected (one column per signal)")
        bad = ~np.isfinite(a)
        if bad.any():
            i, s = np.argwhere(bad)[0]
            raise InputError(f"acceleration: sample {self.samples + i + 1} of signal {s + 1} is "
                             f"{a[i, s]} (every sample must be a finite number)")
        if a.shape[0] == 0:
            return
        a = np.ascontiguousarray(a)
        if self.samples == 0:
            self._last[:] = a[0]
            start = 1  # the first sample starts the motion from rest: nothing to step over
        else:
            start = 0
        coef, groups = self._step(self.dt if h is None else float(h))
        _advance(a, start, self._last, coef, groups, self._x, self._v, self._sd, self._up, self._down)
        self._last[:] = a[-1]
        self.samples += a.shape[0]

    def jump(self, values) -> None:
        """The input jumps to ``values`` (one per signal) at the time of the last sample: the
        oscillators' motion is continuous there (x'' + a = -(2 zeta omega x' + omega^2 x) does
        not jump), so nothing is stepped; the next samples continue from the new value."""
        values = np.broadcast_to(np.asarray(values, dtype=float), (self.n_signals,))
        if self.samples == 0:
            raise InputError("acceleration: a jump needs a sample before it")
        self._last[:] = values

    def reset_peaks(self) -> None:
        """Start the peaks afresh from here, the oscillators keeping their motion: the
        spectrum of a window of the history (after a transient, say)."""
        self._sd[:] = 0.0
        self._up[:] = 0.0
        self._down[:] = 0.0

    def result(self) -> Spectrum:
        """The spectrum of the samples seen so far (copies: updating later does not change it)."""
        shape = (self.n_signals, len(self.periods), len(self.dampings))

        def unordered(peaks):
            out = np.empty_like(peaks)
            out[:, self._order] = peaks
            return np.ascontiguousarray(out.reshape(shape).transpose(1, 2, 0))

        return Spectrum(periods=self.periods.copy(), dampings=self.dampings.copy(), dt=self.dt,
                        samples=self.samples, sd=unordered(self._sd),
                        sa=unordered(np.maximum(self._up, self._down)))


def response_spectrum(acc, dt: float, periods=None, dampings=(0.05,), points_per_period: int = 20) -> Spectrum:
    """Spectra of a whole history: ``acc`` of shape (n,) for one signal or (n, signals).

    ``periods`` default to :func:`default_periods`. The result is bit-identical to that of
    a :class:`SpectrumAccumulator` fed the same samples in any chunks.
    """
    a = np.asarray(acc, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise InputError(f"acceleration: {a.ndim} dimensions where (n,) or (n, signals) was expected")
    stream = SpectrumAccumulator(default_periods() if periods is None else periods, dampings,
                                 a.shape[1], dt, points_per_period)
    stream.update(a)
    return stream.result()


def _checked_oscillators(periods, dampings) -> tuple[np.ndarray, np.ndarray]:
    problems = []
    t = np.atleast_1d(np.asarray(periods, dtype=float))
    z = np.atleast_1d(np.asarray(dampings, dtype=float))
    if t.ndim != 1 or t.size == 0:
        problems.append("periods: one or more periods (s) expected")
    else:
        problems += [f"periods: {v} s must be positive and finite" for v in t if not (math.isfinite(v) and v > 0)]
    if z.ndim != 1 or z.size == 0:
        problems.append("dampings: one or more damping ratios expected")
    else:
        problems += [f"dampings: {v} must be at least 0 and below 1 (an underdamped oscillator)"
                     for v in z if not (0.0 <= v < 1.0)]
    if problems:
        raise InputError(problems)
    return t.copy(), z.copy()


@njit(cache=True, error_model="numpy", inline="always")
def _turning_value(f0, f1, d0, d1, h):
    """The value at its turning point of the cubic with values f0, f1 and slopes d0, d1 at the
    ends of a step h (the Hermite interpolant), where the slopes have opposite signs; else (or
    for h = 0: the points alone) f1."""
    if d0 * d1 >= 0.0 or h == 0.0:
        return f1
    # p(s) = f0 + s h d0 + s^2 c2 + s^3 c3 on s in [0, 1]; p'(s) = h d0 + 2 c2 s + 3 c3 s^2 changes
    # sign in (0, 1): exactly one root there, found without cancellation
    c2 = 3.0 * (f1 - f0) - h * (2.0 * d0 + d1)
    c3 = 2.0 * (f0 - f1) + h * (d0 + d1)
    b = 2.0 * c2
    c = h * d0
    a = 3.0 * c3
    disc = max(b * b - 4.0 * a * c, 0.0)
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    s = c / q if q != 0.0 else 0.5
    if not 0.0 <= s <= 1.0 and a != 0.0:
        s = q / a
    s = min(max(s, 0.0), 1.0)
    return f0 + s * (h * d0 + s * (c2 + s * c3))


@njit(cache=True, error_model="numpy")
def _advance(acc, start, last, coef, groups, x, v, sd, up, down):
    """Step every oscillator (column of coef) for every signal (column of acc) over acc[start:].

    last[s]: the sample before acc[start] of signal s; x, v, sd, up, down: (signals, oscillators)
    state and running peaks, updated in place: max |x|, and the largest y = 2 zeta omega x' +
    omega^2 x (the absolute acceleration's negative peak, as a magnitude) and the largest -y (its
    positive peak): max(up, down) is sa, and the shock spectra keep the two apart. groups[g] = (first, end, m): oscillators
    first..end-1 take m substeps per step, the input interpolated linearly inside the step with
    the same arithmetic whatever the chunking. Between two evaluation points x and the absolute
    acceleration are smooth and their values and slopes at both points are known exactly (the
    slope of x'' + a = -(2 zeta omega x' + omega^2 x) from the equation itself): where a slope
    changes sign, the peak is taken on the cubic through them (Hermite), so a peak between the
    points is found to O(h^4): a sinusoid evaluated 20 times a period peaks within 3e-5 of its
    amplitude, where the points alone can miss it by 1.2 %. The innermost loop runs over the
    oscillators of a group, which do not depend on each other.
    """
    n = acc.shape[0]
    for g in range(groups.shape[0]):
        lo = groups[g, 0]
        hi = groups[g, 1]
        m = groups[g, 2]
        # slices indexed from 0: the compiler sees non-negative indices and vectorises
        a11 = coef[0, lo:hi]
        a12 = coef[1, lo:hi]
        a21 = coef[2, lo:hi]
        a22 = coef[3, lo:hi]
        b11 = coef[4, lo:hi]
        b12 = coef[5, lo:hi]
        b21 = coef[6, lo:hi]
        b22 = coef[7, lo:hi]
        cv = coef[8, lo:hi]
        cx = coef[9, lo:hi]
        hs = coef[10, lo:hi]
        for s in range(acc.shape[1]):
            xs = x[s, lo:hi]
            vs = v[s, lo:hi]
            ds = sd[s, lo:hi]
            us = up[s, lo:hi]
            ws = down[s, lo:hi]
            a0 = last[s]
            for i in range(start, n):
                a1 = acc[i, s]
                da = (a1 - a0) / m
                p0 = a0
                for k in range(1, m + 1):
                    p1 = a0 + k * da if k < m else a1
                    for o in range(hi - lo):
                        xo = xs[o]
                        vo = vs[o]
                        xn = (a11[o] * xo + a12[o] * vo) + (b11[o] * p0 + b12[o] * p1)
                        vn = (a21[o] * xo + a22[o] * vo) + (b21[o] * p0 + b22[o] * p1)
                        yo = cv[o] * vo + cx[o] * xo
                        yn = cv[o] * vn + cx[o] * xn
                        # x'' = -(a + y): the slopes of y = 2 zeta omega x' + omega^2 x at both ends
                        go = cx[o] * vo - cv[o] * (p0 + yo)
                        gn = cx[o] * vn - cv[o] * (p1 + yn)
                        xs[o] = xn
                        vs[o] = vn
                        ds[o] = max(ds[o], abs(_turning_value(xo, xn, vo, vn, hs[o])), abs(xn))
                        turn = _turning_value(yo, yn, go, gn, hs[o])
                        us[o] = max(us[o], turn, yn)
                        ws[o] = max(ws[o], -turn, -yn)
                    p0 = p1
                a0 = a1
