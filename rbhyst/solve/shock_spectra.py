"""Shock response spectra in the terms of ISO 18431-4: positive and negative, primary and residual.

Each oscillator of natural frequency f (omega = 2 pi f) and damping ratio zeta (Q = 1 / (2 zeta))
is driven at its base by the acceleration a(t), sampled at a uniform dt and linear between
samples, and stepped by the exact recurrence and kernel of rbhyst.solve.spectra (Nigam and Jennings 1969),
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

from rbhyst.errors import InputError
from rbhyst.model.periods import octave_frequencies  # noqa: F401 (re-exported beside the spectra it grids)
from rbhyst.solve.spectra import _advance, step_coefficients, substep_counts

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
        return np.fmax(self.primary_positive, self.residual_positive)

    @property
    def negative(self) -> np.ndarray:
        return np.fmax(self.primary_negative, self.residual_negative)

    @property
    def maximax(self) -> np.ndarray:
        return np.fmax(self.primary, self.residual)

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
    problems = oscillator_problems(f, z)
    if not (math.isfinite(dt) and dt > 0):
        problems.append(f"dt: {dt!r} s must be positive")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        problems.append(f"acceleration: sample {bad[0] + 1} is {a[bad[0]]} (every sample must be a finite number)")
    if problems:
        raise InputError(problems)
    acc_ = ShockAccumulator(f, z, 1, dt, points_per_period)
    if a.size >= 1:
        acc_.update(a[:, None])
        acc_.end_primary()
        acc_.update(np.zeros((residual_samples(f, z, dt), 1)))
    else:
        acc_.end_primary()
    return acc_.result()[0]


def oscillator_problems(f: np.ndarray, z: np.ndarray) -> list[str]:
    """One line per frequency or damping an oscillator cannot have."""
    problems = [f"frequencies: {v:g} Hz must be positive and finite" for v in f if not (math.isfinite(v) and v > 0)]
    problems += [f"dampings: {v:g} must be at least 0 and below 1" for v in z if not 0.0 <= v < 1.0]
    if f.size == 0 or z.size == 0:
        problems.append("frequencies, dampings: at least one of each")
    return problems


class ShockAccumulator:
    """The running shock spectrum of ``n_signals`` accelerations fed chunk by chunk.

    ``update(chunk, h)`` steps every oscillator over the next samples, ``h`` apart (the first of a
    chunk follows the last before it by ``h``); the peaks are the primary ones until
    :meth:`end_primary`, the residual ones after it. Any split of a history gives results
    bit-identical to feeding it whole (each oscillator carries x, x' and the last sample), and
    only the state (signals x frequencies x dampings) is held: a run of any length streams.
    """

    def __init__(self, frequencies_hz, dampings, n_signals: int, dt: float, points_per_period: int = 20):
        f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
        z = np.atleast_1d(np.asarray(dampings, dtype=float))
        problems = oscillator_problems(f, z)
        if problems:
            raise InputError(problems)
        self.frequencies_hz, self.dampings = f.copy(), z.copy()
        self.dt, self.n_signals, self.points_per_period = float(dt), int(n_signals), int(points_per_period)
        self._omega = np.repeat(2.0 * np.pi * f, len(z))  # oscillator o = frequency i, damping j at i * nz + j
        self._zeta = np.tile(z, len(f))
        self._steps: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        n = len(self._omega)
        # per signal and oscillator: x, x', max |x|, and the largest y = 2 zeta omega x' + omega^2 x
        # and -y (the absolute acceleration is -y: its negative and positive peaks)
        self._x, self._v, self._sd, self._up, self._down = (np.zeros((self.n_signals, n)) for _ in range(5))
        self._last = np.zeros(self.n_signals)
        self._primary: tuple[np.ndarray, np.ndarray] | None = None  # positive, negative, once ended
        self.samples = 0

    def _step(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(coefficients, groups) of every oscillator for samples h apart, computed once per h:
        the oscillators ascend in frequency, so their substep counts never decrease along them
        and each count is one contiguous group (first, end, m) for the kernel."""
        if h not in self._steps:
            m = substep_counts(2.0 * np.pi / self._omega, h, self.points_per_period)
            edges = np.flatnonzero(np.diff(m)) + 1
            first = np.concatenate([[0], edges])
            end = np.concatenate([edges, [len(m)]])
            groups = np.ascontiguousarray(np.stack([first, end, m[first]], axis=1), dtype=np.int64)
            coef = np.empty((11, len(self._omega)))
            coef[:8] = step_coefficients(self._omega, self._zeta, h / m).T
            coef[8] = 2.0 * self._zeta * self._omega
            coef[9] = self._omega * self._omega
            coef[10] = h / m if self.points_per_period > 0 else 0.0
            self._steps[h] = (coef, groups)
        return self._steps[h]

    def update(self, chunk, h: float | None = None) -> None:
        """The next samples (n, n_signals), SI."""
        a = np.ascontiguousarray(np.asarray(chunk, dtype=float).reshape(-1, self.n_signals))
        if a.shape[0] == 0:
            return
        start = 0
        if self.samples == 0:
            self._last[:] = a[0]
            start = 1  # the first sample starts the motion from rest
        coef, groups = self._step(self.dt if h is None else float(h))
        _advance(a, start, self._last, coef, groups, self._x, self._v, self._sd, self._up, self._down)
        self._last[:] = a[-1]
        self.samples += a.shape[0]

    def update_until(self, chunk, h: float | None, times, switch: float | None) -> None:
        """:meth:`update` with the samples' ``times``: the primary spectrum ends at the last
        sample at or before ``switch`` (s; None: it does not end here)."""
        if switch is None or times is None or self._primary is not None:
            self.update(chunk, h)
            return
        a = np.asarray(chunk, dtype=float).reshape(-1, self.n_signals)
        k = int(np.searchsorted(np.asarray(times, dtype=float), switch * (1.0 + 1e-12) + 1e-15, side="right"))
        self.update(a[:k], h)
        if k < len(a):
            self.end_primary()
            self.update(a[k:], h)

    def jump(self, values) -> None:
        """The input jumps to ``values`` at the last sample's time (the motion is continuous)."""
        self._last[:] = np.broadcast_to(np.asarray(values, dtype=float), (self.n_signals,))

    def end_primary(self) -> None:
        """The excitation ends here: the peaks so far are the primary ones; the residual ones
        start from the absolute acceleration here (the free vibration starts from this state)."""
        if self._primary is not None:
            return
        self._primary = (self._down.copy(), self._up.copy())
        y = 2.0 * self._zeta * self._omega * self._v + self._omega * self._omega * self._x
        self._down[:] = np.maximum(-y, 0.0)
        self._up[:] = np.maximum(y, 0.0)

    def result(self) -> list[ShockSpectrum]:
        """One ShockSpectrum a signal; the residual is NaN where the excitation has not ended."""
        shape = (len(self.frequencies_hz), len(self.dampings))
        out = []
        for s in range(self.n_signals):
            if self._primary is None:
                pp, pn = self._down[s], self._up[s]
                rp = rn = np.full(len(self._omega), np.nan)
            else:
                pp, pn, rp, rn = self._primary[0][s], self._primary[1][s], self._down[s], self._up[s]
            out.append(ShockSpectrum(self.frequencies_hz.copy(), self.dampings.copy(), self.dt, self.samples,
                                     *(np.array(v).reshape(shape) for v in (pp, pn, rp, rn, self._sd[s]))))
        return out
