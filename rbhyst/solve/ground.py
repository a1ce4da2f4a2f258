"""The response spectra of the support motion, from its signals themselves, not from its samples at dt.

A run's ground spectrum is that of the acceleration the analysis follows (rbhyst.model.system.Excitation):

- a record is linear between its samples: the oscillators are driven at its own samples (exact
  for that input, whatever the run's dt) and then by rest, as ``rbhyst spectrum`` drives them;
- an analytic sine or pulse is smooth between its breakpoints (start, end, corners): each piece
  is sampled FINE_POINTS times per period or duration (the error of taking it as linear between
  those points, (pi / FINE_POINTS)^2 / 8 of its amplitude, is 8e-6), and a jump at a breakpoint is
  a jump of the input at one instant (the oscillators' motion is continuous through it), not a
  ramp over a step of dt. Where the signal is zero the oscillators vibrate freely, evaluated as
  ``points_per_period`` asks.
"""

from __future__ import annotations

import math

import numpy as np

from rbhyst.model.records import Series
from rbhyst.solve.located import GROUND, LocatedSpectra
from rbhyst.solve.spectra import SpectrumAccumulator

#: samples per sine period or per pulse duration within an analytic signal's span
FINE_POINTS = 400


def ground_spectra(excitation, t_end: float, dampings, periods) -> LocatedSpectra:
    """Spectra of every support acceleration of ``excitation`` over [0, t_end] (those it has, x1, x2, then x3)."""
    labels, parts, record_dt = [], [], []
    for k, signal in ((1, excitation.ag1), (2, excitation.ag2), (3, excitation.ag3)):
        if signal is None:
            continue
        if isinstance(signal, Series):
            record_dt.append((f"x{k}", float(signal.dt)))
        acc = SpectrumAccumulator(periods, dampings, 1, dt=_nominal_step(signal))
        for h, values, jump in signal_chunks(signal, t_end, max(periods)):
            if jump is not None:
                acc.jump(jump)
            acc.update(values, h)
        labels.append((GROUND, f"x{k}"))
        parts.append(acc.result())
    if not parts:
        n_p, n_d = len(np.atleast_1d(periods)), len(np.atleast_1d(dampings))
        from rbhyst.solve.spectra import Spectrum

        empty = np.zeros((n_p, n_d, 0))
        spectrum = Spectrum(periods=np.asarray(periods, float), dampings=np.asarray(dampings, float), dt=0.0,
                            samples=0, sd=empty, sa=empty.copy())
        return LocatedSpectra((), spectrum)
    first = parts[0]
    spectrum = type(first)(periods=first.periods, dampings=first.dampings, dt=first.dt, samples=first.samples,
                           sd=np.concatenate([p.sd for p in parts], axis=2),
                           sa=np.concatenate([p.sa for p in parts], axis=2))
    return LocatedSpectra(tuple(labels), spectrum, tuple(record_dt))


def _nominal_step(signal) -> float:
    return signal.dt if isinstance(signal, Series) else signal.step * 40.0 / FINE_POINTS


def signal_chunks(signal, t_end: float, longest_period: float):
    """(h, values, jump) in time order: chunks of samples h apart from t = 0 (the first
    chunk's first sample at t = 0) that together are the signal over [0, t_end]; ``jump``, when
    not None, is the value the input jumps to at the previous chunk's last sample."""
    if isinstance(signal, Series):
        yield from _record_chunks(signal, t_end)
    else:
        yield from _analytic_chunks(signal, t_end, longest_period)


def _record_chunks(signal: Series, t_end: float):
    """The record at its own samples (from rest at t = 0 until a late first sample, where it
    jumps in), then rest at its own step, as rbhyst spectrum appends it: exactly the input the
    record is, linear between its samples, whatever the run's dt."""
    dt, t0 = signal.dt, signal.t0
    times = t0 + dt * np.arange(len(signal.values))
    values = signal.values[times <= t_end * (1.0 + 1e-12)]
    if t0 > 0.0:
        yield t0, np.zeros(2), None
        if len(values) > 1:
            yield dt, values[1:], values[0]
        elif len(values):
            yield 0.0, np.zeros(0), values[0]
    elif len(values):
        yield dt, values, None
    t_last = t0 + dt * (len(values) - 1) if len(values) else 0.0
    after = t_end - t_last
    if after <= 1e-12 * max(1.0, t_end):
        return
    if len(values) < len(signal.values):  # the analysis ends between two samples: the value there
        yield after, signal(np.array([t_end])), None
        return
    n_rest = int(math.ceil(after / dt - 1e-9))
    if n_rest > 1:
        yield dt, np.zeros(n_rest - 1), None
    yield after - dt * (n_rest - 1), np.zeros(1), None


def _analytic_chunks(signal, t_end: float, longest_period: float):
    """A sine or pulse piece by piece between its breakpoints: FINE_POINTS samples a feature
    where it acts, free vibration (20 samples of the longest period) where it is zero; a jump
    at a breakpoint is one."""
    fine = signal.step * 40.0 / FINE_POINTS
    coarse = longest_period / 20.0
    cuts = np.unique([0.0, t_end, *(b for b in signal.breakpoints if 0.0 < b < t_end)])
    start, stop = signal.start, (math.inf if signal.end is None else signal.end)
    first = True
    prev_right = None
    for a, b in zip(cuts[:-1], cuts[1:]):
        mid = 0.5 * (a + b)
        on = start <= mid <= stop
        n = max(1, int(math.ceil((b - a) / (fine if on else coarse) - 1e-9)))
        t = a + (b - a) * np.arange(n + 1) / n
        t[-1] = b
        values = signal.inside(t) if on else np.zeros(n + 1)
        if first:
            yield (b - a) / n, values, None
            first = False
        else:
            jump = values[0] if values[0] != prev_right else None
            yield (b - a) / n, values[1:], jump
        prev_right = values[-1]
