"""An SRS specification (a CSV of breakpoints) and the tolerance a shock's SRS is held to.

The file: ``frequency_hz`` and a value column whose header states its unit (``srs_g``,
``srs_m_s2``, ``srs [g]``), the maximax absolute-acceleration SRS at the Q the command is
given; between breakpoints the specification is straight on log-log axes (a constant dB an
octave), as shock specifications are drawn.

The tolerance is MIL-STD-810G Method 516.6 / 810H Method 516.8's for a shock specified by its
SRS (paragraph 4.2.2): the maximax SRS, analysed at Q = 10 on 1/12-octave frequencies, within
-1.5 dB and +3 dB of the specification. The standard lets some frequencies fall outside (up to
10 % of them, within -3 dB and +6 dB); rbhyst holds every 1/12-octave frequency of the
specification's range to -1.5/+3 dB, the stricter reading. Other standards differ (NASA-STD-7003A
holds pyroshock to wider bands at 1/6 octave): give the tested-to document's band with the
test plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.analyses.qualification.rrs import ACCEL_TO_SI, acceleration_column
from rbhyst.errors import InputError
from rbhyst.files.curves import read_curve

#: the band, dB about the specification (MIL-STD-810G 516.6 / 810H 516.8, 4.2.2)
LOWER_DB, UPPER_DB = -1.5, 3.0
#: the frequencies checked an octave
PER_OCTAVE = 12
G = 9.80665


@dataclass(frozen=True)
class Specification:
    """Breakpoints ``frequency_hz`` and ``srs`` (m/s2, maximax absolute acceleration) at ``q``."""

    name: str
    frequency_hz: np.ndarray
    srs: np.ndarray

    def __call__(self, f) -> np.ndarray:
        """The specification at ``f`` (Hz), straight between breakpoints on log-log axes."""
        return np.exp(np.interp(np.log(f), np.log(self.frequency_hz), np.log(self.srs)))

    def frequencies(self) -> np.ndarray:
        """The 1/12-octave frequencies of its range (its lowest to its highest breakpoint)."""
        from rbhyst.solve.shock_spectra import octave_frequencies

        return octave_frequencies(float(self.frequency_hz[0]), float(self.frequency_hz[-1]), PER_OCTAVE)


def read_specification(path: Path) -> Specification:
    """A specification from a CSV; problems name the file and line."""
    path = Path(path)
    curve = read_curve(path, "an SRS specification")
    unit, problems = acceleration_column(path, curve, "an SRS", "frequency_hz,srs_g (or srs_m_s2, ...)")
    if len(curve.x) < 2:
        problems.append(f"{path}: at least two breakpoints (a range of frequencies)")
    if problems:
        raise InputError(problems)
    return Specification(path.stem, curve.x.copy(), curve.y * ACCEL_TO_SI[unit.name])


def ratio_db(computed, spec) -> np.ndarray:
    return 20.0 * np.log10(np.asarray(computed, float) / np.asarray(spec, float))


def within(db) -> np.ndarray:
    return (np.asarray(db) >= LOWER_DB) & (np.asarray(db) <= UPPER_DB)


def q_problems(q: float, key: str = "--q") -> list[str]:
    if not (math.isfinite(q) and q > 0.5):
        return [f"{key}: {q:g}: a quality factor above 0.5 (Q = 1 / (2 damping); 10 for 5 %)"]
    return []
