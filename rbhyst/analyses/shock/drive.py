"""The acceleration a shock test plays along one axis: the shock (a classical pulse or a record)
``shocks`` times in a row, each after the free vibration of the one before has had its time.

MIL-STD-810H Method 516.8 Procedure I asks for three shocks in each direction of each axis. A
rate-independent mount starting at rest would answer a repeated shock as it answered the first
only if it came back to where it started; a Vaiana-Rosati mount generally keeps a residual
deformation (and a body under gravity settles), so the shocks are played one after the other in
one run and the hysteresis carries over, as on the test table: each shock's own peaks are
reported beside the run's (rbhyst.analyses.shock.verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError

G = 9.80665


@dataclass(frozen=True)
class Drive:
    """``values`` (m/s2) at ``dt`` from t = 0: the shock ``shocks`` times, each ``period`` s after
    the one before (the shock's own ``length`` s, then rest); ``pulse`` the classical pulse (None
    for a record), ``source`` what the shock is."""

    values: np.ndarray
    dt: float
    shocks: int
    length: float
    period: float
    source: str
    pulse: object = None

    @property
    def end(self) -> float:
        """The end of the last shock, s."""
        return (self.shocks - 1) * self.period + self.length

    def windows(self) -> list[tuple[float, float]]:
        """(from, to) s of each shock and the rest after it (the last to the end of the run)."""
        return [(k * self.period, (k + 1) * self.period if k < self.shocks - 1 else math.inf)
                for k in range(self.shocks)]

    def one(self) -> np.ndarray:
        """One shock's samples."""
        return self.values[:round(self.length / self.dt) + 1]

    def text(self, mark: str) -> str:
        """The drive as a record file: time_s,acceleration_g."""
        t = self.dt * np.arange(len(self.values))
        rows = "\n".join(f"{ti:.9g},{a:.10g}" for ti, a in zip(t, self.values / G))
        return f"{mark}\ntime_s,acceleration_g\n{rows}\n"


def repeated(one: np.ndarray, dt: float, shocks: int, gap: float, source: str, pulse=None) -> Drive:
    """``one`` shock (samples at ``dt`` from rest) ``shocks`` times, ``gap`` s of rest after each."""
    rest = max(1, math.ceil(gap / dt))
    block = np.concatenate([one, np.zeros(rest)])
    values = np.concatenate([np.tile(block, shocks - 1), one]) if shocks > 1 else one.copy()
    return Drive(values, dt, shocks, (len(one) - 1) * dt, len(block) * dt, source, pulse)


def pulse_drive(spec, shocks: int, gap: float) -> Drive:
    """A classical pulse (rbhyst.model.shock_pulses) as a drive; ``spec``: (kind, peak m/s2, duration
    s, compensation, ratio, rise s or None, what it is)."""
    from rbhyst.model.shock_pulses import classical_pulse

    kind, peak, duration, compensation, ratio, rise, source = spec
    p = classical_pulse(kind, peak, duration, 0.0, compensation, ratio, rise)
    return repeated(np.asarray(p.series.values, float), p.series.dt, shocks, gap, source, p)


def record_drive(path: Path, units: str, scale: float, dt: float | None, shocks: int, gap: float,
                 where: str) -> Drive:
    """A record as a drive (from rest: a record that does not start at zero jumps in)."""
    from rbhyst.files.units import check_declared
    from rbhyst.model.deck import ACCEL_UNITS
    from rbhyst.model.records import read_record

    try:
        rec = read_record(Path(path), dt)
        check_declared(rec.declared, units)
    except InputError as err:
        raise InputError([f"{where}: {p}" for p in err.problems]) from None
    if rec.series.t0 != 0.0:
        raise InputError(f"{where}: {Path(path).name}: its time column starts at {rec.series.t0:g} s: a shock record "
                         "starts at 0 s")
    one = np.asarray(rec.series.values, float) * ACCEL_UNITS[units] * scale
    return repeated(one, float(rec.series.dt), shocks, gap, f"the record {Path(path).name}")
