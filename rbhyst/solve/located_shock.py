"""Shock response spectra of a run (``[output.spectra] kind = "srs"``): of the ground, of G and of
every point, each along its directions, in the terms of ISO 18431-4.

The body's accelerations stream through one :class:`~rbhyst.solve.shock_spectra.ShockAccumulator`
as the rows are computed, at every compute step, like the response spectra
(:mod:`rbhyst.solve.located`). The spectrum is *primary* up to the end of the excitation (the
latest end of its support motions and forces) and *residual* after it, until the analysis ends:
the residual spectrum is the body's free vibration as computed, which only the analysis's
duration bounds (a note says when it ends too soon for the lowest frequency). Where the
excitation never ends (a sine without end) there is no residual spectrum (NaN in srs.csv).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.solve.located import GROUND
from rbhyst.solve.shock_spectra import SRS_COLUMNS, ShockAccumulator, ShockSpectrum

#: srs.csv's columns in a run: the location and direction, then those of `rbhyst spectrum --kind srs`
RUN_SRS_COLUMNS = ("location", "direction") + SRS_COLUMNS


def excitation_end(excitation) -> float | None:
    """When the excitation (every support motion and force) has ended; None if it never does."""
    ends = [signal.end for signal in excitation.signals.values()]
    return max(ends) if ends and None not in ends else (0.0 if not ends else None)


@dataclass(frozen=True)
class LocatedShockSpectra:
    """One ShockSpectrum per entry of ``signals``, (location, direction) each, on the same
    frequencies and dampings; ``record_dt`` as LocatedSpectra's."""

    signals: tuple[tuple[str, str], ...]
    spectra: tuple[ShockSpectrum, ...]
    record_dt: tuple[tuple[str, float], ...] = ()
    #: when the primary spectrum ended (the excitation's end), None if it never did
    switch: float | None = None

    kind = "srs"

    @property
    def locations(self) -> list[str]:
        return list(dict.fromkeys(loc for loc, _ in self.signals))

    def of(self, location: str, direction: str) -> ShockSpectrum:
        return self.spectra[self.signals.index((location, direction))]

    def sa(self, location: str, direction: str) -> np.ndarray:
        """(frequencies, dampings) maximax absolute acceleration, m/s2 (what the estimate compares)."""
        return self.of(location, direction).maximax

    def maximax_spectra(self):
        """The maximax as a LocatedSpectra (sa: maximax, sd: max |x|, periods 1 / the frequencies,
        longest first as the frequencies ascend): what spectra.png's drawing takes."""
        from rbhyst.solve.located import LocatedSpectra
        from rbhyst.solve.spectra import Spectrum

        first = self.spectra[0]
        spectrum = Spectrum(periods=1.0 / first.frequencies_hz, dampings=first.dampings.copy(), dt=first.dt,
                            samples=first.samples, sd=np.stack([s.sd for s in self.spectra], axis=2),
                            sa=np.stack([s.maximax for s in self.spectra], axis=2))
        return LocatedSpectra(self.signals, spectrum, self.record_dt)

    def joined(self, other: "LocatedShockSpectra") -> "LocatedShockSpectra":
        return LocatedShockSpectra(self.signals + other.signals, self.spectra + other.spectra,
                                   self.record_dt + other.record_dt, other.switch)

    def table(self) -> tuple[list[tuple[str, str]], np.ndarray]:
        """The rows of srs.csv: (location, direction) of each and its numbers (SRS_COLUMNS)."""
        labels, numbers = [], []
        for label, s in zip(self.signals, self.spectra):
            rows = s.table()
            labels += [label] * len(rows)
            numbers.append(rows)
        return labels, np.vstack(numbers) if numbers else np.empty((0, len(SRS_COLUMNS)))

    def summary(self, file: str = "srs.csv") -> dict:
        """summary.json's entry: what was computed and each curve's largest maximax."""
        first = self.spectra[0] if self.spectra else None
        peaks = []
        for (loc, direction), s in zip(self.signals, self.spectra):
            for j, q in enumerate(s.qs):
                i = int(np.nanargmax(s.maximax[:, j]))
                peaks.append({"location": loc, "direction": direction, "q": float(q),
                              "maximax_m_s2": float(s.maximax[i, j]), "frequency_hz": float(s.frequencies_hz[i]),
                              "pv_m_s": float(np.max(s.pv[:, j]))})
        return {"file": file, "kind": "srs", "qs": [] if first is None else [float(q) for q in first.qs],
                "frequencies_hz": {} if first is None else {
                    "min": float(first.frequencies_hz.min()), "max": float(first.frequencies_hz.max()),
                    "count": int(len(first.frequencies_hz))},
                "primary_until_s": self.switch, "locations": self.locations, "peaks": peaks}


class ShockSink:
    """Running shock spectra of named signals fed chunk by chunk with their times: primary up to
    ``switch`` (s; None: never), residual after."""

    def __init__(self, signals, dampings, periods, dt: float, switch: float | None):
        self.signals = tuple(signals)
        self.switch = switch
        frequencies = np.sort(1.0 / np.asarray(periods, dtype=float))
        self._acc = ShockAccumulator(frequencies, dampings, len(self.signals), dt)

    def update(self, chunk: np.ndarray, h: float | None = None, times: np.ndarray | None = None) -> None:
        """The next rows, ``h`` apart, at ``times`` (s)."""
        self._acc.update_until(chunk, h, times, self.switch)

    def result(self) -> LocatedShockSpectra:
        return LocatedShockSpectra(self.signals, tuple(self._acc.result()), switch=self.switch)


def ground_shock_spectra(excitation, t_end: float, dampings, periods) -> LocatedShockSpectra:
    """The shock spectra of every support acceleration of ``excitation`` over [0, t_end], from its
    signal itself (rbhyst.solve.ground.signal_chunks), primary up to the excitation's end."""
    from rbhyst.model.records import Series
    from rbhyst.solve.ground import signal_chunks

    switch = excitation_end(excitation)
    frequencies = np.sort(1.0 / np.asarray(periods, dtype=float))
    labels, parts, record_dt = [], [], []
    for k, signal in ((1, excitation.ag1), (2, excitation.ag2), (3, excitation.ag3)):
        if signal is None:
            continue
        if isinstance(signal, Series):
            record_dt.append((f"x{k}", float(signal.dt)))
        acc = ShockAccumulator(frequencies, dampings, 1, dt=1.0)
        t = None
        for h, values, jump in signal_chunks(signal, t_end, float(np.max(periods))):
            if jump is not None:
                acc.jump(jump)
            n = len(values)
            if n == 0:
                continue
            times = (h * np.arange(n) if t is None else t + h * np.arange(1, n + 1))
            acc.update_until(np.asarray(values, float)[:, None], h, times, switch)
            t = times[-1]
        labels.append((GROUND, f"x{k}"))
        parts.append(acc.result()[0])
    return LocatedShockSpectra(tuple(labels), tuple(parts), tuple(record_dt), switch)


def residual_note(spectra: LocatedShockSpectra, end_of_analysis: float) -> str | None:
    """A note when the analysis ends before one damped period of the lowest frequency has
    passed after the excitation: the residual spectrum there may not have reached its peaks."""
    if spectra.switch is None:
        return ("output.spectra: the excitation lasts the whole analysis, so there is no residual "
                "spectrum (srs.csv gives NaN there; maximax, positive and negative are the primary's)")
    if not spectra.spectra:
        return None
    s = spectra.spectra[0]
    need = 1.0 / (float(s.frequencies_hz.min()) * math.sqrt(1.0 - float(s.dampings.max()) ** 2))
    after = end_of_analysis - spectra.switch
    if after >= need:
        return None
    return (f"output.spectra: the analysis ends {after:.4g} s after the excitation, and the residual "
            f"spectrum of the lower frequencies (from {float(s.frequencies_hz.min()):.4g} Hz) needs one "
            f"damped period of free vibration: analysis.duration = {spectra.switch + need:.4g} s gives it")
