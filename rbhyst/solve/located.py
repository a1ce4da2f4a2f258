"""Response spectra of named acceleration histories: the ground, the mass centre G and the
body's points of interest, each along x1 and x2.

:class:`SpectraSink` streams a run's total accelerations through one
:class:`~rbhyst.solve.spectra.SpectrumAccumulator` as the rows are computed, so a run of
any length holds only the oscillators' state; :class:`LocatedSpectra` is what comes out,
with the long-form rows of spectra.csv and the summary's entry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.solve.spectra import Spectrum, SpectrumAccumulator

#: spectra.csv's columns, one row per location, direction, damping and period
SPECTRA_COLUMNS = ("location", "direction", "damping", "period_s", "frequency_hz", "sa_m_s2", "psa_m_s2", "sd_m")
GROUND, CENTRE = "ground", "G"


@dataclass(frozen=True)
class LocatedSpectra:
    """``spectrum`` has one signal per entry of ``signals``, (location, direction) each;
    ``record_dt`` the sample step of each ground motion that is a record, (direction, s): its
    content ends at the Nyquist frequency 1 / (2 dt), whatever the oscillators' range."""

    signals: tuple[tuple[str, str], ...]
    spectrum: Spectrum
    record_dt: tuple[tuple[str, float], ...] = ()

    #: what they are (LocatedShockSpectra: "srs"), as the writers and figures tell them apart
    kind = "sa"

    @property
    def locations(self) -> list[str]:
        return list(dict.fromkeys(loc for loc, _ in self.signals))

    def index(self, location: str, direction: str) -> int:
        return self.signals.index((location, direction))

    def sa(self, location: str, direction: str) -> np.ndarray:
        """(periods, dampings) max |absolute acceleration|, m/s2."""
        return self.spectrum.sa[:, :, self.index(location, direction)]

    def sd(self, location: str, direction: str) -> np.ndarray:
        return self.spectrum.sd[:, :, self.index(location, direction)]

    def joined(self, other: "LocatedSpectra") -> "LocatedSpectra":
        """These signals followed by ``other``'s (same periods and dampings); the samples and dt
        are ``other``'s (a run's ground spectra joined by its body's, which count its rows)."""
        a, b = self.spectrum, other.spectrum
        spectrum = Spectrum(periods=b.periods, dampings=b.dampings, dt=b.dt, samples=b.samples,
                            sd=np.concatenate([a.sd, b.sd], axis=2), sa=np.concatenate([a.sa, b.sa], axis=2))
        return LocatedSpectra(self.signals + other.signals, spectrum, self.record_dt + other.record_dt)

    def nyquist_hz(self, direction: str | None = None) -> float | None:
        """The Nyquist frequency of the ground record along ``direction`` (without, or without
        a record there: the lowest of every record's); None without a record."""
        steps = dict(self.record_dt)
        if direction in steps:
            return 0.5 / steps[direction]
        return 0.5 / max(steps.values()) if steps else None

    def table(self) -> tuple[list[tuple[str, str]], np.ndarray]:
        """The rows of spectra.csv: (location, direction) of each and its numbers (damping,
        period_s, frequency_hz, sa_m_s2, psa_m_s2, sd_m)."""
        s = self.spectrum
        periods, dampings = s.periods, s.dampings
        psa = s.psa
        labels, numbers = [], []
        for k, label in enumerate(self.signals):
            for j, zeta in enumerate(dampings):
                labels += [label] * len(periods)
                numbers.append(np.column_stack([np.full(len(periods), zeta), periods, 1.0 / periods,
                                                s.sa[:, j, k], psa[:, j, k], s.sd[:, j, k]]))
        return labels, np.vstack(numbers) if numbers else np.empty((0, 6))

    def summary(self, file: str = "spectra.csv") -> dict:
        """A short entry for summary.json: what was computed and each curve's peak."""
        s = self.spectrum
        peaks = []
        for loc, direction in self.signals:
            sa = self.sa(loc, direction)
            for j, zeta in enumerate(s.dampings):
                i = int(np.argmax(sa[:, j]))
                peaks.append({"location": loc, "direction": direction, "damping": float(zeta),
                              "sa_m_s2": float(sa[i, j]), "period_s": float(s.periods[i])})
        return {"file": file, "dampings": [float(z) for z in s.dampings],
                "periods_s": {"min": float(s.periods.min()), "max": float(s.periods.max()),
                              "count": int(len(s.periods))},
                "dt_s": s.dt, "samples": s.samples, "locations": self.locations, "peaks": peaks}


class SpectraSink:
    """Running spectra of named signals fed chunk by chunk: (n, signals) arrays in order."""

    def __init__(self, signals, dampings, periods, dt: float):
        self.signals = tuple(signals)
        self._acc = SpectrumAccumulator(periods, dampings, len(self.signals), dt)

    def update(self, chunk: np.ndarray, h: float | None = None, times=None) -> None:
        """The next rows, ``h`` apart (default the sink's dt; their ``times`` are not needed)."""
        self._acc.update(chunk, h)

    def result(self) -> LocatedSpectra:
        return LocatedSpectra(self.signals, self._acc.result())


def rest_samples(periods, dampings, dt: float) -> int:
    """Samples of zero input after which every oscillator has passed its largest response.

    Once the input has ramped to zero (one step), each oscillator vibrates freely: x and the
    absolute acceleration are damped sinusoids of the damped period Td = T / sqrt(1 - zeta^2),
    whose extrema fall Td / 2 apart and shrink from one to the next; the largest is therefore
    the one where the free vibration starts or the first after it, within Td / 2.
    """
    td = max(periods) / math.sqrt(1.0 - max(dampings) ** 2)
    return 1 + math.ceil(0.5 * td / dt - 1e-9)


def unfinished_note(end_of_excitation: float | None, end_of_analysis: float, periods, dampings) -> str | None:
    """A note when the analysis stops before the longest oscillators can reach their peak."""
    if end_of_excitation is None:
        return None
    need = 0.5 * max(periods) / math.sqrt(1.0 - max(dampings) ** 2)
    after = end_of_analysis - end_of_excitation
    if after >= need:
        return None
    when = (f"the analysis ends {after:.4g} s after the excitation" if after >= 0.0 else
            f"the analysis ends at {end_of_analysis:.4g} s, before the excitation does ({end_of_excitation:.4g} s)")
    return (f"output.spectra: {when}, and oscillators "
            f"of the longer periods (up to {max(periods):.4g} s) may reach their peak later: "
            f"analysis.duration = {end_of_excitation + need:.4g} s lets every one of them ring out "
            "(the ground is at rest then, and the body's free vibration is computed)")
