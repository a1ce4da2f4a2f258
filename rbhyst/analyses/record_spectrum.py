"""The response spectrum of a support acceleration record alone (``rbhyst spectrum``)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.solve.located import GROUND, LocatedSpectra, SpectraSink, rest_samples
from rbhyst.solve.spectra import default_periods

#: what the record readers say of the deck, said of the command's options instead
_OPTION_WORDS = (("one column of values needs `dt` in the deck", "one column of values needs --dt"),
                 ("has a time column; leave `dt` out of the deck", "has a time column; leave --dt out"),
                 ("but the deck says units =", "but --units says"))


def check_oscillators(dampings, periods) -> list[str]:
    """Problems with --damping and --periods, one line each."""
    problems = [f"--damping: {z:g} must be at least 0 and below 1" for z in dampings if not 0.0 <= z < 1.0]
    problems += [f"--periods: {t:g} s must be positive" for t in periods or () if not (t > 0 and math.isfinite(t))]
    if len(set(dampings)) != len(dampings):
        problems.append("--damping: each damping once")
    if periods is not None and len(set(periods)) != len(periods):
        problems.append("--periods: each period once")
    if not dampings:
        problems.append("--damping: at least one damping ratio")
    if periods is not None and not periods:
        problems.append("--periods: at least one period (s)")
    return problems


def record_spectrum(path: Path, units: str, dt: float | None = None, dampings=(0.05,), periods=None,
                    direction: str = "x1", free_vibration: bool = True) -> LocatedSpectra:
    """Spectra of the record at ``path`` in ``units`` (held to what the file declares).

    free_vibration: follow the record with rest until every oscillator has passed its peak
    (rest_samples: exact, as the ground is at rest after the record); otherwise peaks over
    the record's samples only.
    """
    from rbhyst.model.deck import ACCEL_UNITS

    problems = check_oscillators(list(dampings), None if periods is None else list(periods))
    if units not in ACCEL_UNITS:
        problems.append(f"--units: {units!r} is not an acceleration unit rbhyst knows; "
                        f"choose one of {', '.join(ACCEL_UNITS)}")
    if dt is not None and not (dt > 0 and math.isfinite(dt)):
        problems.append(f"--dt: {dt:g} s must be positive")
    if direction not in ("x1", "x2"):
        problems.append(f"--direction: {direction!r}: x1 or x2")
    if problems:
        raise InputError(problems)
    rec, acc = _read(path, units, dt)
    periods = np.sort(np.asarray(periods, float)) if periods is not None else default_periods()
    sink = SpectraSink([(GROUND, direction)], dampings, periods, rec.series.dt)
    sink.update(acc[:, None])
    if free_vibration:
        sink.update(np.zeros((rest_samples(periods, dampings, rec.series.dt), 1)))
    return dataclasses.replace(sink.result(), record_dt=((direction, float(rec.series.dt)),))


def _read(path: Path, units: str, dt: float | None):
    """The record and its samples in m/s2, the readers' words about the deck said of the options."""
    from rbhyst.files.units import check_declared
    from rbhyst.model.deck import ACCEL_UNITS
    from rbhyst.model.records import read_record

    try:
        rec = read_record(Path(path), dt)
        check_declared(rec.declared, units)
    except InputError as err:
        lines = []
        for p in err.problems:
            for deck_words, option_words in _OPTION_WORDS:
                p = p.replace(deck_words, option_words)
            lines.append(p)
        raise InputError(lines) from None
    return rec, rec.series.values * ACCEL_UNITS[units]


def default_srs_frequencies(dt: float, per_octave: int = 12) -> np.ndarray:
    """1 Hz to the lesser of 10 kHz and a tenth of the sample rate (rbhyst.model.periods.srs_range),
    ``per_octave`` an octave."""
    from rbhyst.model.periods import octave_frequencies, srs_range

    return octave_frequencies(*srs_range(dt), per_octave)


def record_shock_spectrum(path: Path, units: str, dt: float | None = None, qs=(10.0,),
                          frequencies: tuple[float, float] | None = None, per_octave: int = 12):
    """The shock response spectrum (rbhyst.solve.shock_spectra) of the record at ``path`` in
    ``units``: primary over its samples, residual over the free vibration after them; damping
    1 / (2 Q) for every Q; ``frequencies`` (lowest, highest) Hz at ``per_octave`` an octave
    (default: default_srs_frequencies)."""
    from rbhyst.model.deck import ACCEL_UNITS
    from rbhyst.model.periods import octave_frequencies
    from rbhyst.solve.shock_spectra import shock_spectrum

    problems = [f"--q: {q:g} must be above 0.5 (an underdamped oscillator, damping 1 / (2 Q) below 1)"
                for q in qs if not (q > 0.5)]
    if len(set(qs)) != len(qs):
        problems.append("--q: each Q once")
    if not qs:
        problems.append("--q: at least one Q")
    if units not in ACCEL_UNITS:
        problems.append(f"--units: {units!r} is not an acceleration unit rbhyst knows; "
                        f"choose one of {', '.join(ACCEL_UNITS)}")
    if dt is not None and not (dt > 0 and math.isfinite(dt)):
        problems.append(f"--dt: {dt:g} s must be positive")
    if problems:
        raise InputError(problems)
    rec, acc = _read(path, units, dt)
    step = float(rec.series.dt)
    f = (default_srs_frequencies(step, per_octave) if frequencies is None
         else octave_frequencies(frequencies[0], frequencies[1], per_octave))
    return shock_spectrum(acc, step, f, [1.0 / (2.0 * q) if math.isfinite(q) else 0.0 for q in qs])
