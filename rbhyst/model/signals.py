"""Analytic excitation signals: sines and shock pulses, in SI units.

Each is a callable of time with what a time stepper needs to follow it exactly: ``end``
(after it the signal is zero; None for a sine without end), ``step`` (the longest step that
resolves its shape: POINTS_PER_FEATURE steps per period or per pulse, so that no feature
falls between steps however short it is against dt) and ``breakpoints`` (where it starts,
stops or has a corner: the adaptive integrator puts a step boundary there).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: an analytic signal as one row of floats, for compiled code that evaluates it exactly
#: (rbhyst.solve.kernels.dop853): kind, amplitude, omega, phase, start, stop (inf: none), ramp, duration
SINE, HALF_SINE, HAVERSINE, SAWTOOTH, TRIANGLE = range(5)
ROW_SIZE = 8

#: steps per sine period or per pulse: the load is linear between compute steps, and at 40 a
#: half-sine's impulse is followed to 0.1 % (1 - (pi/40)^2/12 of the exact 2/pi A T)
POINTS_PER_FEATURE = 40


@dataclass(frozen=True)
class Sine:
    """amplitude sin(omega (t - start) + phase) from ``start`` to ``stop`` (None: for ever),
    its amplitude rising over the first ``ramp`` seconds by :func:`ramp_envelope`."""

    amplitude: float
    omega: float
    phase: float
    start: float
    stop: float | None
    ramp: float = 0.0

    def __call__(self, t) -> np.ndarray:
        """The signal at t; at its start and stop it has its span's value (the span is closed)."""
        t = np.asarray(t, dtype=float)
        on = t >= self.start if self.stop is None else (t >= self.start) & (t <= self.stop)
        return np.where(on, self.inside(t), 0.0)

    def inside(self, t) -> np.ndarray:
        """The sine's formula at t, as it is within its span (the limit at either end)."""
        t = np.asarray(t, dtype=float)
        value = self.amplitude * np.sin(self.omega * (t - self.start) + self.phase)
        if self.ramp > 0.0:
            value = value * ramp_envelope((t - self.start) / self.ramp)
        return value

    @property
    def end(self) -> float | None:
        return self.stop

    @property
    def step(self) -> float:
        return 2.0 * math.pi / self.omega / POINTS_PER_FEATURE

    @property
    def breakpoints(self) -> tuple[float, ...]:
        ramp = (self.start + self.ramp,) if self.ramp > 0.0 and (self.stop is None or
                                                                 self.start + self.ramp < self.stop) else ()
        return (self.start, *ramp) if self.stop is None else (self.start, *ramp, self.stop)

    def acts_before(self, t_end: float) -> bool:
        return self.amplitude != 0.0 and self.start < t_end

    def row(self) -> list[float]:
        """This signal as a row of the compiled evaluator's table (see ROW_SIZE)."""
        stop = math.inf if self.stop is None else self.stop
        return [SINE, self.amplitude, self.omega, self.phase, self.start, stop, self.ramp, 0.0]


def _half_sine(tau):
    return np.sin(np.pi * tau)


def _haversine(tau):
    return 0.5 * (1.0 - np.cos(2.0 * np.pi * tau))


def _terminal_peak_sawtooth(tau):
    return tau


def _triangle(tau):
    return 1.0 - np.abs(2.0 * tau - 1.0)


#: pulse shapes on tau = (t - start) / duration in [0, 1], peak 1; where they have corners; their
#: kind in the compiled evaluator's table
SHAPES = {
    "half-sine": (_half_sine, (), HALF_SINE),
    "haversine": (_haversine, (), HAVERSINE),
    "terminal-peak-sawtooth": (_terminal_peak_sawtooth, (), SAWTOOTH),  # drops to zero at tau = 1
    "triangle": (_triangle, (0.5,), TRIANGLE),
}


@dataclass(frozen=True)
class Pulse:
    """A shock pulse of peak ``amplitude`` over [start, start + duration], zero elsewhere."""

    kind: str
    amplitude: float
    duration: float
    start: float

    def __call__(self, t) -> np.ndarray:
        """The pulse at t; at its start and end it has its span's value (the span is closed)."""
        t = np.asarray(t, dtype=float)
        tau = (t - self.start) / self.duration
        return np.where((tau >= 0.0) & (tau <= 1.0), self.inside(t), 0.0)

    def inside(self, t) -> np.ndarray:
        """The pulse's shape at t, as it is within its span (the limit at either end)."""
        tau = (np.asarray(t, dtype=float) - self.start) / self.duration
        return self.amplitude * SHAPES[self.kind][0](np.clip(tau, 0.0, 1.0))

    @property
    def end(self) -> float:
        return self.start + self.duration

    @property
    def step(self) -> float:
        return self.duration / POINTS_PER_FEATURE

    @property
    def breakpoints(self) -> tuple[float, ...]:
        corners = SHAPES[self.kind][1]
        return (self.start, *(self.start + c * self.duration for c in corners), self.end)

    def acts_before(self, t_end: float) -> bool:
        return self.amplitude != 0.0 and self.start < t_end

    def row(self) -> list[float]:
        """This pulse as a row of the compiled evaluator's table (see ROW_SIZE)."""
        return [SHAPES[self.kind][2], self.amplitude, 0.0, 0.0, self.start, self.end, 0.0, self.duration]


def ramp_envelope(tau) -> np.ndarray:
    """0 before tau = 0, tau - sin(2 pi tau) / (2 pi) up to 1, then 1.

    Its slope 1 - cos(2 pi tau) is a Hann window: the envelope joins 0 and 1 with zero slope
    and zero curvature, so the free vibration a ramped sine leaves in a linear oscillator of
    frequency omega_0 falls as 1 / (|omega - omega_0| T_ramp)^3 (a shaker's ramp: the steady
    state without the transient of an abrupt start).
    """
    tau = np.clip(np.asarray(tau, dtype=float), 0.0, 1.0)
    return tau - np.sin(2.0 * np.pi * tau) / (2.0 * np.pi)


def sine(amplitude: float, frequency_hz: float, phase_deg: float = 0.0, start: float = 0.0,
         cycles: float | None = None, ramp_cycles: float = 0.0) -> Sine:
    stop = None if cycles is None else start + cycles / frequency_hz
    return Sine(amplitude, 2.0 * math.pi * frequency_hz, math.radians(phase_deg), start, stop,
                ramp_cycles / frequency_hz)


@functools.cache
def _gauss() -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [0, 1] for each half of a hat (exact for polynomials
    of degree 15 times the hat's linear weight: far below the step's own error for smooth
    pieces). On first use: numpy.polynomial costs a command milliseconds to import."""
    x, w = np.polynomial.legendre.leggauss(8)
    return 0.5 * (x + 1.0), 0.5 * w


def hat_average(signal, t: np.ndarray, h: float) -> np.ndarray:
    """(1/h) integral of signal(t_k + s) (1 - |s|/h) ds over |s| < h, for every node t_k.

    Each half of a hat is integrated piece by piece between the signal's breakpoints (where it
    starts, stops or has a corner), so a jump or a kink costs nothing.
    """
    t = np.asarray(t, dtype=float)
    gx, gw = _gauss()
    out = np.zeros(len(t))
    for side in (-1.0, 1.0):
        # the half [t_k, t_k + side h]: u in [0, 1] along it, weight (1 - u)
        a = np.zeros(len(t))
        cuts = [np.zeros(len(t)), np.ones(len(t))]
        for b in signal.breakpoints:
            u = side * (b - t) / h
            cuts.append(np.where((u > 0.0) & (u < 1.0), u, 0.0))
        cuts = np.sort(np.column_stack(cuts), axis=1)
        for j in range(cuts.shape[1] - 1):
            lo, hi = cuts[:, j], cuts[:, j + 1]
            span = hi - lo
            live = span > 0.0
            if not live.any():
                continue
            u = lo[live, None] + span[live, None] * gx[None, :]
            vals = signal(t[live, None] + side * h * u)
            a[live] += span[live] * ((vals * (1.0 - u)) @ gw)
        out += a
    return out
