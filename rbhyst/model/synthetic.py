"""Reproducible synthetic ground acceleration: Clough-Penzien filtered white noise.

The seed's Fig. 5 record is not published, so its sample deck uses records made
here. White noise from a seeded generator passes through the Kanai-Tajimi soil
filter (omega_g, zeta_g) and the Clough-Penzien high-pass (omega_f, zeta_f), both
discretized by the bilinear transform, is shaped by a Jennings envelope (t^2
build-up, strong phase, exponential decay), has its baseline removed so that
velocity and displacement end near zero, and is scaled to the target peak.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal


def _second_order(num, den, dt):
    b, a = signal.bilinear(num, den, fs=1.0 / dt)
    return b, a


def envelope(t: np.ndarray, rise: float, strong: float, decay: float) -> np.ndarray:
    """Jennings et al. (1968): (t/t1)^2, 1, exp(-c (t - t2))."""
    t1, t2 = rise, rise + strong
    e = np.ones_like(t)
    e[t < t1] = (t[t < t1] / t1) ** 2
    late = t > t2
    e[late] = np.exp(-decay * (t[late] - t2))
    return e


def ground_motion(
    duration: float = 40.0,
    dt: float = 0.01,
    pga: float = 0.3,
    seed: int = 1940,
    f_g: float = 2.5,
    zeta_g: float = 0.6,
    f_f: float = 0.25,
    zeta_f: float = 0.6,
    rise: float = 2.0,
    strong: float = 8.0,
    decay: float = 0.18,
) -> tuple[np.ndarray, np.ndarray]:
    """(t, a) with max |a| = pga, in the units pga is given in."""
    n = int(round(duration / dt)) + 1
    t = dt * np.arange(n)
    rng = np.random.default_rng(seed)
    w = rng.standard_normal(n)
    wg, wf = 2 * math.pi * f_g, 2 * math.pi * f_f
    # Kanai-Tajimi: (2 zg wg s + wg^2) / (s^2 + 2 zg wg s + wg^2)
    b, a = _second_order([2 * zeta_g * wg, wg * wg], [1.0, 2 * zeta_g * wg, wg * wg], dt)
    x = signal.lfilter(b, a, w)
    # Clough-Penzien high-pass: s^2 / (s^2 + 2 zf wf s + wf^2)
    b, a = _second_order([1.0, 0.0, 0.0], [1.0, 2 * zeta_f * wf, wf * wf], dt)
    x = signal.lfilter(b, a, x)
    x *= envelope(t, rise, strong, decay)
    x = baseline_corrected(x, dt)
    return t, x * (pga / np.max(np.abs(x)))


def baseline_corrected(acc: np.ndarray, dt: float) -> np.ndarray:
    """Remove the quadratic displacement trend (a least-squares fit of the doubly
    integrated record) so that the support does not drift away."""
    t = dt * np.arange(len(acc))
    vel = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)])
    disp = np.concatenate([[0.0], np.cumsum(0.5 * (vel[1:] + vel[:-1]) * dt)])
    # fit disp ~ c2 t^2 + c3 t^3 (starts at rest): its second derivative is the drift
    basis = np.vstack([t**2, t**3]).T
    c, *_ = np.linalg.lstsq(basis, disp, rcond=None)
    return acc - (2 * c[0] + 6 * c[1] * t)
