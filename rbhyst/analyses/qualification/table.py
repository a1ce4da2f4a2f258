"""A shake table's limits: the drive displacement (peak to peak, the actuator's stroke), the
peak velocity and the peak acceleration a record may ask of it.

A record made for a table must fit them. Its displacement and velocity come mostly from its
content below the RRS's check range, which the TRS needs only in part: matching.match lets
that content go from ``high_pass`` x the lowest checked frequency (a smooth high-pass, 0 an
octave below it), and rbhyst raises the corner step by step (HIGH_PASS_STEPS) until the record
fits, the TRS kept in its band on the fine grid; its acceleration is capped where the RRS's
least peak allows. Where no step fits, the command stops (exit 3) with the limit, the least
the record reached and what would fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.analyses.qualification.rrs import G
from rbhyst.errors import InputError
#: the high-pass corners tried, in multiples of the lowest checked frequency (0.5: the default,
#: content from a quarter of it)
HIGH_PASS_STEPS = (0.5, 0.6, 0.7, 0.85, 1.0, 1.15, 1.3)
#: each limit is met with this margin (the file's rounding, the table's controller)
MARGIN = 0.01
KEYS = {"displacement": "m, peak to peak", "velocity": "m/s, peak", "acceleration": "g, peak"}


@dataclass(frozen=True)
class Table:
    """The limits (None: no limit): displacement peak to peak (m), velocity (m/s) and
    acceleration (g), both peaks."""

    displacement: float | None = None
    velocity: float | None = None
    acceleration: float | None = None

    def describe(self) -> dict:
        return {"displacement_peak_to_peak_m": self.displacement, "velocity_m_s": self.velocity,
                "acceleration_g": self.acceleration}

    def reached(self, acc: np.ndarray, dt: float) -> dict:
        """What a record (m/s2) asks of the table: displacement peak to peak, peak velocity
        (of the record linear between its samples, from rest) and peak acceleration (g)."""
        from rbhyst.model.baseline import integrate

        v, d = integrate(acc, dt)
        return {"displacement": float(np.ptp(d)), "velocity": float(np.max(np.abs(v))),
                "acceleration": float(np.max(np.abs(acc))) / G}

    def over(self, reached: dict) -> list[str]:
        """The limits ``reached`` is beyond (with the margin)."""
        return [k for k in KEYS if getattr(self, k) is not None and reached[k] > getattr(self, k) * (1.0 - MARGIN)]


def parse_table(text: str | None, key: str = "--table") -> Table | None:
    """``displacement=D,velocity=V,acceleration=A`` (any of them, m peak to peak, m/s, g)."""
    table, problems = read_table(text, key)
    if problems:
        raise InputError(problems)
    return table


def read_table(text: str | None, key: str = "--table") -> tuple[Table | None, list[str]]:
    """parse_table's limits (those that read) and its problems, one line each."""
    if text is None:
        return None, []
    values, problems = {}, []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or name not in KEYS:
            problems.append(f"{key}: {part!r}: name=value with displacement (m, peak to peak), velocity (m/s) or "
                            "acceleration (g)")
            continue
        try:
            x = float(value)
        except ValueError:
            problems.append(f"{key}: {name}={value!r}: a number ({KEYS[name]})")
            continue
        if not (x > 0 and math.isfinite(x)):
            problems.append(f"{key}: {name}={value}: must be positive ({KEYS[name]})")
            continue
        values[name] = x
    if not values and not problems:
        problems.append(f"{key}: {text!r}: at least one of displacement=, velocity=, acceleration=")
    return (Table(**values) if values else None), problems


def table_problems(table: Table | None, peak_min_g: dict[str, float | None], key: str = "--table") -> list[str]:
    """What no record can do: a peak acceleration limit below the least the RRS asks for."""
    if table is None or table.acceleration is None:
        return []
    return [f"{key}: acceleration={table.acceleration:g} g is below the least peak the RRS of {axis} asks for "
            f"({least:.4g} g): no record can meet both" for axis, least in peak_min_g.items()
            if least is not None and table.acceleration < least]


def said(name: str, value: float) -> str:
    unit = {"displacement": "m peak to peak", "velocity": "m/s", "acceleration": "g"}[name]
    return f"{value:.3g} {unit}"
