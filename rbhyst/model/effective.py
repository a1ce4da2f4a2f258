"""Effective (secant) properties of a VRM set on its steady symmetric cycle of amplitude A: what an
isolator catalogue gives (ISO 22762 / AASHTO-style secant stiffness and equivalent damping).

The cycle is displacement-controlled: from the virgin state to +A, then cycles +A -> -A -> +A.
A VRM loop is not closed after one cycle: along a branch the distance to the limiting curve
decays as exp(-alpha |u - u_P|) (seed eq. 14), so the reversal forces approach those of the
steady loop by the factor exp(-2 A (alpha+ + alpha-)) per cycle (the map from one cycle's
reversal force to the next is affine with that slope). At small alpha A one settling cycle
leaves much of the virgin loading in (at alpha A = 0.2, 45 % of the initial offset), so the
settling goes on until that factor has shrunk below 1e-15: the cycle measured is the steady
loop, up to rounding. The settling takes two samples per cycle (the VRM is exact between any
two displacements of one direction); the measured cycle is sampled finely for plots, its work
(the loop's area) is the model's closed-form work, not a quadrature.

    k_eff = (F(+A) - F(-A)) / 2A,   W = loop area,   beta_eff = W / (2 pi k_eff A^2)

and k_reversal, the tangent just after a reversal of that cycle (eq. 16; the mean of the
reversals at +A and -A): the stiffness of small vibrations superposed on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.model.hysteresis import ALPHA, limiting_curve, limiting_slope
from rbhyst.model.vrm import loop

#: the settling goes on until the distance to the steady loop has shrunk by this factor
SETTLED = 1e-15
#: ... but no longer than this many cycles (an amplitude so small that alpha A < 2e-5)
MAX_SETTLING = 10**6
#: samples per half cycle of the measured (plotted) cycle
HALF = 200

COLUMNS = ("set", "amplitude_m", "k_eff_N_m", "beta_eff", "energy_J")


@dataclass(frozen=True)
class Effective:
    """One set's steady cycle of amplitude A and its effective properties (SI)."""

    amplitude: float  # A [m]
    f_plus: float  # F(+A) [N]
    f_minus: float  # F(-A) [N]
    energy: float  # W, the loop's area [J]
    k_reversal: float  # tangent just after a reversal (mean of +A and -A) [N/m]
    settling_cycles: int
    u: np.ndarray  # the measured cycle, +A -> -A -> +A [m]
    f: np.ndarray  # [N]

    @property
    def k_eff(self) -> float:
        return (self.f_plus - self.f_minus) / (2.0 * self.amplitude)

    @property
    def beta_eff(self) -> float:
        k = self.k_eff
        return self.energy / (2.0 * math.pi * k * self.amplitude ** 2) if k > 0 else math.inf

    def row(self, name: str) -> dict:
        """effective.csv's row."""
        return {"set": name, "amplitude_m": self.amplitude, "k_eff_N_m": self.k_eff,
                "beta_eff": self.beta_eff, "energy_J": self.energy}


def settling_cycles(p: np.ndarray, amplitude: float) -> int:
    """Cycles after which the reversal forces are those of the steady loop to SETTLED (at least 1)."""
    rate = 2.0 * amplitude * (float(p[0, ALPHA]) + float(p[1, ALPHA]))
    if not rate > 0.0:  # (a deck's alpha is > 0; a fit's may underflow)
        return MAX_SETTLING
    return int(min(MAX_SETTLING, max(1, math.ceil(-math.log(SETTLED) / rate))))


def effective(p: np.ndarray, amplitude: float) -> Effective:
    """The steady symmetric cycle of amplitude ``amplitude`` > 0 of set ``p`` (2, 8) and its
    effective properties; OverflowError where the set's exponentials overflow at that amplitude."""
    a = float(amplitude)
    if not a > 0.0:
        raise ValueError(f"amplitude {a!r}: must be > 0")
    n = settling_cycles(p, a)
    half = np.linspace(a, -a, HALF + 1)
    cycle = np.concatenate([half[1:], half[-2::-1]])  # +A (excluded) -> -A -> +A
    u = np.concatenate([[a], np.tile([-a, a], n), cycle])
    f, _, w = loop(p, u)
    start = 2 * n  # the sample at +A before the measured cycle
    uc, fc = u[start:], f[start:]
    energy = float(w[-1] - w[start])
    # eq. 16 just after each reversal: from f at the reversal, on the new branch
    k_down = _tangent_after(p, -1, a, float(f[start]))
    k_up = _tangent_after(p, 1, -a, float(f[start + HALF]))
    return Effective(a, float(f[-1]), float(f[start + HALF]), energy, 0.5 * (k_down + k_up), n,
                     uc.copy(), fc.copy())


def _tangent_after(p: np.ndarray, s: int, u: float, f: float) -> float:
    """Eq. 16 at the start of a branch of sign s at (u, f): kc_s(u) + s alpha_s (c_s(u) - f)."""
    row = 0 if s > 0 else 1
    return float(limiting_slope(p, s, u)) + s * float(p[row, ALPHA]) * (float(limiting_curve(p, s, u)) - f)


def table(sets: dict[str, np.ndarray], amplitudes) -> list[dict]:
    """effective.csv's rows: every set at every amplitude, in that order."""
    return [effective(p, a).row(name) for name, p in sets.items() for a in amplitudes]
