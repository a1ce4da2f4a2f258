"""How long a record's strong motion lasts, measured three ways, and the requirement checked.

- **Bracketed duration** (the standards' definition): from the first time |a| reaches a
  fraction of its peak to the last time it falls below it. IEEE Std 693-2005, Annex A (its
  time-history test) and IEEE Std 344 define the strong part of a test motion so, at 25 % of
  the peak, and ask for at least 20 s of it. ICC-ES AC156 asks for 20 s of strong motion within
  30 s but does not define it; rbhyst holds an AC156 motion to the same definition, the one
  shake-table practice takes from the IEEE standards (a test lab reads both from the same
  record of the table).
- **Arias (significant) durations**: the time between 5 % and 95 %, and 5 % and 75 %, of the
  Arias intensity, the integral of a^2 (Trifunac and Brady, 1975; Bommer, Stafford and Alarcon,
  2009): reported beside, not checked; the 5-75 % duration is much shorter than the bracketed
  one for an envelope with ramps (a 30 s make-motion record: about 15-18 s against 24-26 s).

The bracketed duration's crossings are found on the record linear between its samples (as the
analysis takes it); the intensity is integrated by the trapezoidal rule.
"""

from __future__ import annotations

import numpy as np

#: the bracketed duration's level, a fraction of the peak |a| (IEEE 693, IEEE 344)
BRACKET = 0.25
DEFINITION = ("bracketed: from the first time |a| reaches 25 % of its peak to the last time it falls below it "
              "(IEEE Std 693-2005 Annex A and IEEE Std 344 define it so; rbhyst holds every standard's motions to it)")


def arias_duration(acc: np.ndarray, dt: float, lo: float = 0.05, hi: float = 0.95) -> float:
    """Time between ``lo`` and ``hi`` of the Arias intensity: the integral of a^2 by the
    trapezoidal rule, as strong-motion processing computes it (the exact integral of the record
    linear between its samples differs by a few hundredths of a second at 8 samples a cycle)."""
    e = np.concatenate([[0.0], np.cumsum(0.5 * dt * (acc[:-1] ** 2 + acc[1:] ** 2))])
    if e[-1] <= 0.0:
        return 0.0
    t = dt * np.arange(len(acc))
    return float(np.interp(hi * e[-1], e, t) - np.interp(lo * e[-1], e, t))


def bracketed_duration(acc: np.ndarray, dt: float, fraction: float = BRACKET) -> float:
    """From the first time |a| reaches ``fraction`` of its peak to the last time it leaves that
    level, the crossings between samples found on the straight line between them."""
    mag = np.abs(acc)
    level = fraction * float(mag.max(initial=0.0))
    above = np.flatnonzero(mag >= level)
    if level <= 0.0 or len(above) == 0:
        return 0.0
    i, j = int(above[0]), int(above[-1])
    # a sample inside (-level, level) and the next outside it: the line between them crosses
    # the level once, on the outer sample's side
    start = dt * i if i == 0 else dt * (i - 1 + _reach(acc[i - 1], acc[i], level))
    end = dt * j if j == len(acc) - 1 else dt * (j + 1 - _reach(acc[j + 1], acc[j], level))
    return float(end - start)


def _reach(inside: float, outside: float, level: float) -> float:
    """Where, as a fraction of the step from ``inside`` to ``outside``, the line between them
    reaches the level on ``outside``'s side."""
    target = level if outside > 0 else -level
    return min(max((target - inside) / (outside - inside), 0.0), 1.0)


def measured(acc: np.ndarray, dt: float) -> dict:
    """The three durations of a record (m/s2), in s."""
    return {"bracketed_25_s": bracketed_duration(acc, dt), "arias_5_75_s": arias_duration(acc, dt, 0.05, 0.75),
            "arias_5_95_s": arias_duration(acc, dt, 0.05, 0.95)}


def strong_part_ratio(acc: np.ndarray, dt: float) -> float:
    """IEEE 693's strong part ratio: the 25-75 % Arias duration over the 5-95 % one."""
    whole = arias_duration(acc, dt)
    return arias_duration(acc, dt, 0.25, 0.75) / whole if whole > 0.0 else 0.0
