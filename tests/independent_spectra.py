"""Response spectra and strong-motion durations computed here, apart from rbhyst's own code, to
check it: the exact discretisation of a linear oscillator under an input linear between samples
(scipy.linalg.expm of the augmented system) run as an IIR filter (scipy.signal.lfilter), the
Arias intensity by the trapezoidal rule, the bracketed duration from the samples."""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter, ss2tf


def trs(acc: np.ndarray, dt: float, freqs, zeta: float, sub: int = 4) -> np.ndarray:
    """The peak absolute acceleration of each oscillator (Hz, damping ratio ``zeta``) under the
    record (m/s2, linear between its samples) followed by 10 periods of the lowest at rest, read
    at ``sub`` points a sample step (the peaks between samples, within 0.3 % at 4)."""
    freqs = np.asarray(freqs, float)
    a = np.concatenate([acc, np.zeros(int(10.0 / freqs.min() / dt))])
    h = dt / sub
    a = np.interp(np.arange((len(a) - 1) * sub + 1) * h, np.arange(len(a)) * dt, a)
    ahead = np.append(a[1:], 0.0)
    out = np.empty(len(freqs))
    for k, f in enumerate(freqs):
        w = 2.0 * np.pi * f
        A = np.zeros((4, 4))  # [u, v, ag, ag'], ag' constant over a step
        A[0, 1], A[1, 0], A[1, 1], A[1, 2], A[2, 3] = 1.0, -w * w, -2.0 * zeta * w, -1.0, 1.0
        P = expm(A * h)
        Ad, Ba, Bs = P[:2, :2], P[:2, 2], P[:2, 3]  # x+ = Ad x + Ba a_i + Bs (a_{i+1} - a_i) / h
        C = np.array([[-w * w, -2.0 * zeta * w]])  # absolute acceleration
        n0, den = ss2tf(Ad, (Ba - Bs / h)[:, None], C, np.zeros((1, 1)))
        n1, _ = ss2tf(Ad, (Bs / h)[:, None], C, np.zeros((1, 1)))
        out[k] = np.max(np.abs(lfilter(n0[0], den, a) + lfilter(n1[0], den, ahead)))
    return out


def octave_grid(lo: float, hi: float, per_octave: int = 48) -> np.ndarray:
    n = int(np.floor(per_octave * np.log2(hi / lo) + 1e-9))
    f = lo * 2.0 ** (np.arange(n + 1) / per_octave)
    return f if f[-1] >= hi * (1 - 1e-9) else np.append(f, hi)


def arias_duration(acc: np.ndarray, dt: float, lo: float, hi: float) -> float:
    """Time from ``lo`` to ``hi`` of the Arias intensity (the integral of a^2, trapezoids)."""
    e = np.concatenate([[0.0], np.cumsum(0.5 * dt * (acc[:-1] ** 2 + acc[1:] ** 2))])
    t = dt * np.arange(len(acc))
    return float(np.interp(hi * e[-1], e, t) - np.interp(lo * e[-1], e, t))


def bracketed_duration(acc: np.ndarray, dt: float, fraction: float = 0.25) -> float:
    """From the first to the last sample whose |a| reaches ``fraction`` of the peak."""
    k = np.flatnonzero(np.abs(acc) >= fraction * np.abs(acc).max())
    return float((k[-1] - k[0]) * dt)
