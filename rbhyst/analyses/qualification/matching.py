"""Spectrum-compatible support motions: envelope-shaped band-limited noise whose Fourier
amplitudes are iterated until its response spectrum (the TRS) lies in the RRS's band.

The method (the stationary-process-times-envelope form of Gasparini and Vanmarcke's SIMQKE,
1976, with the Fourier-amplitude iteration spectral-matching codes such as REQPY apply to
their wavelet details):

1. Gaussian white noise from numpy's PCG64 (``default_rng([seed, motion, stream])``: the same
   seed gives the same numbers on every machine; the stream is 1 for x1, 2 for the vertical
   axis, 3 for a deck in space's second horizontal, x2), its Fourier amplitudes shaped by the RRS and
   band-limited (a smooth high-pass an octave below the checked range, a low-pass towards the
   Nyquist frequency): a stationary process s(t).
2. The motion is e(t) s(t) with an envelope e that rises over the first ramp (a raised cosine),
   holds 1 over the strong-motion part and falls over the last, then corrected to end at rest
   (below).
3. Its TRS is computed at 1/12-octave control frequencies and on the fine grid of the check
   range (1/48 octave, about 160 frequencies a decade: NRC SRP 3.7.1 asks for at least 100, and
   between 1/6-octave points a TRS can dip 10 % below the RRS) by rbhyst.response, the same
   oscillators ``rbhyst spectrum`` uses, the record followed by rest as that command follows
   it; the Fourier amplitudes of s are multiplied by the ratio aimed-at / TRS, interpolated on
   log frequency, and the loop goes on until the TRS lies within the band at every frequency of
   the fine grid (the standard's 1/6-octave points among them), with a margin for the rounding
   of the file. The aim is the middle of the band in logarithm: sqrt(0.9 x 1.3) = 1.08 times
   the RRS for AC156's band, sqrt(1.0 x 1.3) = 1.14 for IEEE 693's.
4. Where the RRS asks for a least peak acceleration (AC156: 0.9 A_RIG; IEEE 693: the ZPA) and
   the record falls short of it, its largest peak is raised to it (with the margin) by the
   shape a peak of the process has on average (its autocorrelation, the transform of its power
   spectrum: given x(t0) = a, a Gaussian process is a rho(t - t0) in the mean), centred on it.

**End at rest.** The record is corrected to end at rest (rbhyst.model.baseline.to_rest): its
final velocity and displacement zero for the record linear between its samples, the
displacement history least within that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rbhyst.analyses.qualification import strong_motion
from rbhyst.model.baseline import integrate, to_rest  # noqa: F401 (integrate: matching's API too)
from rbhyst.errors import AnalysisError
from rbhyst.analyses.qualification.rrs import (AC156_DURATION, AC156_STRONG, G, IEEE693_DURATION, IEEE693_STRONG,
                                               RRS, fine_grid, standard_points)

#: the TRS is aimed at this multiple of the RRS: the middle of the 0.9-1.3 band in logarithm
AIM = math.sqrt(0.9 * 1.3)
#: ... tending to this multiple at the top of the checked range (see match)
TOP_AIM = 1.0
#: the peaks are never cut below this multiple of the RRS at the top of the range
PEAK_FLOOR = 0.95
#: iterations before the motion is declared not matched
MAX_ITERATIONS = 40
#: the loop stops once the TRS is this far inside the band, so that the file's rounding and the
#: check read back from it cannot leave it
MARGIN = 0.02
#: digits of the acceleration (in g) in the files: the TRS checked is that of these values
FILE_FORMAT = "%.9e"
#: at most this fraction of the sampling frequency may be checked (a 33.3 Hz oscillator needs
#: the motion's content around it, linear interpolation between samples costs little below it)
MAX_CHECK_FRACTION = 0.25


def envelope(t: np.ndarray, duration: float, strong: float) -> np.ndarray:
    """Raised-cosine rise over (duration - strong) / 2, 1 over ``strong``, raised-cosine fall."""
    ramp = 0.5 * (duration - strong)
    e = np.ones_like(t)
    if ramp > 0.0:
        up = t < ramp
        e[up] = np.sin(0.5 * np.pi * t[up] / ramp) ** 2
        down = t > duration - ramp
        e[down] = np.sin(0.5 * np.pi * (duration - t[down]) / ramp) ** 2
    return e


def default_strong(duration: float) -> float:
    """Ramps of 5 s (a sixth of a shorter motion each): AC156's 20 s of strong motion in 30 s."""
    return duration - 2.0 * min(5.0, duration / 6.0)


def in_file_digits(acc_g: np.ndarray) -> np.ndarray:
    """The values as the record file holds them (FILE_FORMAT), so that every check is of the file."""
    return np.char.mod(FILE_FORMAT, acc_g).astype(float)


def trs(acc: np.ndarray, dt: float, freqs: np.ndarray, damping: float) -> np.ndarray:
    """sa (m/s2) at ``freqs`` of a record (m/s2) followed by rest, as ``rbhyst spectrum`` computes it."""
    from rbhyst.solve.located import GROUND, SpectraSink, rest_samples

    periods = np.sort(1.0 / np.asarray(freqs, float))
    sink = SpectraSink([(GROUND, "x1")], [damping], periods, dt)
    sink.update(acc[:, None])
    sink.update(np.zeros((rest_samples(periods, [damping], dt), 1)))
    sa = sink.result().spectrum.sa[:, 0, 0]
    order = np.argsort(1.0 / np.asarray(freqs, float))
    out = np.empty(len(sa))
    out[order] = sa
    return out


@dataclass
class Check:
    """The TRS of one record against its RRS at the standard's 1/6-octave frequencies of the check
    range (``frequency_hz``, ``rrs``, ``trs``: trs.csv's rows) and on the fine grid (``fine_hz``,
    ``fine_rrs``, ``fine_trs``: 1/48 octave, which holds the 1/6-octave points; trs_fine.csv),
    and its peak acceleration against the least the RRS asks for (when it asks: ``peak_min``).
    It lies within the band only where it does at every frequency of both."""

    frequency_hz: np.ndarray
    rrs: np.ndarray  # m/s2
    trs: np.ndarray  # m/s2
    band: tuple[float, float]
    peak: float | None = None  # m/s2, the record's peak acceleration
    peak_min: float | None = None  # m/s2, the least it may be (None: not checked)
    fine_hz: np.ndarray | None = None
    fine_rrs: np.ndarray | None = None
    fine_trs: np.ndarray | None = None

    @property
    def ratio(self) -> np.ndarray:
        return self.trs / self.rrs

    @property
    def within(self) -> np.ndarray:
        """At the standard's points."""
        return self._inside(self.ratio)

    @property
    def fine_frequency(self) -> np.ndarray:
        return self.frequency_hz if self.fine_hz is None else self.fine_hz

    @property
    def fine_sa(self) -> np.ndarray:
        """The TRS (m/s2) on the fine grid."""
        return self.trs if self.fine_trs is None else self.fine_trs

    @property
    def fine_ratio(self) -> np.ndarray:
        return self.ratio if self.fine_trs is None else self.fine_trs / self.fine_rrs

    @property
    def fine_within(self) -> np.ndarray:
        """On the fine grid."""
        return self._inside(self.fine_ratio)

    def _inside(self, r: np.ndarray) -> np.ndarray:
        lo, hi = self.band
        return (r >= lo) & (r <= hi)

    @property
    def in_band(self) -> bool:
        return bool(self.within.all()) and bool(self.fine_within.all())

    @property
    def peak_ok(self) -> bool:
        return self.peak_min is None or (self.peak is not None and self.peak >= self.peak_min)

    @property
    def ok(self) -> bool:
        return self.in_band and self.peak_ok

    def summary(self) -> dict:
        """The least and largest ratio anywhere (on the fine grid) and where; the standard's points
        outside the band, and the stretches of the fine grid outside it ([from, to] Hz)."""
        r, f = self.fine_ratio, self.fine_frequency
        i, j = int(np.argmin(r)), int(np.argmax(r))
        return {"pass": self.ok, "band": list(self.band), "frequencies": int(len(self.ratio)),
                "fine_frequencies": int(len(r)),
                "min_ratio": float(r[i]), "min_at_hz": float(f[i]),
                "max_ratio": float(r[j]), "max_at_hz": float(f[j]),
                "outside_hz": [float(x) for x in self.frequency_hz[~self.within]],
                "outside_fine_hz": stretches(f, ~self.fine_within),
                "within_band": self.in_band,
                "peak_g": None if self.peak is None else self.peak / G,
                "peak_min_g": None if self.peak_min is None else self.peak_min / G,
                "peak_pass": self.peak_ok}

    def said_peak(self) -> str:
        """Why the peak fails: it and the least it may be."""
        return (f"its peak acceleration {self.peak / G:.4g} g is below {self.peak_min / G:.4g} g "
                f"({self.peak_min / self.rrs[-1]:g} times the RRS at {self.frequency_hz[-1]:.4g} Hz)")

    def said(self) -> str:
        s = self.summary()
        return (f"{s['min_ratio']:.3f} ({s['min_at_hz']:.3g} Hz) to {s['max_ratio']:.3f} "
                f"({s['max_at_hz']:.3g} Hz) times the RRS")


def stretches(f: np.ndarray, bad: np.ndarray) -> list[list[float]]:
    """The runs of consecutive ``bad`` frequencies, each as [first, last] Hz."""
    out, start = [], None
    for k, b in enumerate(bad):
        if b and start is None:
            start = k
        if start is not None and (not b or k == len(bad) - 1):
            out.append([float(f[start]), float(f[k if b else k - 1])])
            start = None
    return out


def check_record(acc: np.ndarray, dt: float, rrs: RRS) -> Check:
    """The TRS of a record (m/s2) on the fine grid of its RRS's check range, the standard's
    1/6-octave points among them."""
    fine = fine_grid(*rrs.check_range)
    points = standard_points(fine, rrs.check_range)
    sa = trs(acc, dt, fine, rrs.damping)
    return Check(fine[points], rrs(fine[points]), sa[points], rrs.band, float(np.max(np.abs(acc))), rrs.peak_min,
                 fine, rrs(fine), sa)


@dataclass
class Record:
    """One axis of one motion: the acceleration as written (g, FILE_FORMAT digits), its check,
    its strong motion (strong_motion.measured) and the least it may be (None: not checked)."""

    axis: str
    acc_g: np.ndarray
    check: Check
    iterations: int
    durations: dict = field(default_factory=dict)
    strong_min: float | None = None
    plateau: float | None = None  # s, the envelope's plateau it was made on
    table: object = None  # table.Table the record was made within (None: no table)
    high_pass: float | None = None  # Hz, the corner of its high-pass
    reached: dict = field(default_factory=dict)  # what it asks of a table (table.Table.reached)

    @property
    def strong(self) -> float:
        """Its strong motion, as the standards define it (the bracketed duration), s."""
        return self.durations["bracketed_25_s"]

    @property
    def strong_ok(self) -> bool:
        return self.strong_min is None or self.strong >= self.strong_min

    @property
    def table_ok(self) -> bool:
        return self.table is None or not self.table.over(self.reached)

    @property
    def ok(self) -> bool:
        return self.check.ok and self.strong_ok and self.table_ok

    def facts(self, dt: float, rrs: RRS) -> dict:
        acc = self.acc_g * G
        v, d = integrate(acc, dt)
        pga = float(np.max(np.abs(self.acc_g)))
        return {"pga_g": pga, "pga_over_rrs_at_top": pga * G / float(rrs(rrs.check_range[1])),
                "iterations": self.iterations,
                "end_velocity_m_s": float(v[-1]), "end_displacement_m": float(d[-1]),
                "peak_velocity_m_s": float(np.max(np.abs(v))), "peak_displacement_m": float(np.max(np.abs(d))),
                "displacement_peak_to_peak_m": float(np.max(d) - np.min(d)),
                "strong_motion_s": self.strong, "strong_motion_min_s": self.strong_min,
                "strong_motion_pass": self.strong_ok, "strong_motion_definition": strong_motion.DEFINITION,
                **self.durations, "envelope_plateau_s": self.plateau,
                "strong_part_ratio": strong_motion.strong_part_ratio(acc, dt),
                "high_pass_hz": self.high_pass,
                **({} if self.table is None else {"table": {**self.table.describe(), "pass": self.table_ok}}),
                "trs": self.check.summary()}


@dataclass
class Motion:
    """One motion: a record per axis (x1 horizontal, x2 vertical; in space x1 and x2
    horizontal, x3 vertical: ``vertical`` names it), sampled at ``dt``."""

    number: int
    seed: int
    dt: float
    duration: float
    strong: float
    records: dict[str, Record] = field(default_factory=dict)
    vertical: str = "x2"

    @property
    def time(self) -> np.ndarray:
        n = len(next(iter(self.records.values())).acc_g)
        return self.dt * np.arange(n)

    @property
    def correlations(self) -> dict[str, float]:
        """Pearson's correlation coefficient of each pair of axes' accelerations, by ``x1_x2``."""
        axes = list(self.records)
        return {f"{a}_{b}": float(np.corrcoef(self.records[a].acc_g, self.records[b].acc_g)[0, 1])
                for i, a in enumerate(axes) for b in axes[i + 1:]}

    def coherences(self) -> dict[str, dict]:
        """Each pair of axes' magnitude-squared coherence (scipy.signal.coherence, Welch's
        segments of 2.56 s at least, Hann, half overlap) over the check range: its mean and
        largest there. Reported, not judged: AC156 and IEEE 693 hold the components to their
        correlation coefficient; independent records' coherence is small at every frequency
        (its estimate's bias about 1 / segments, some 0.05 here)."""
        from scipy.signal import coherence

        axes = list(self.records)
        nper = int(2 ** math.ceil(math.log2(2.56 / self.dt)))
        out = {}
        for i, a in enumerate(axes):
            for b in axes[i + 1:]:
                ra, rb = self.records[a], self.records[b]
                lo = max(ra.check.fine_frequency[0], rb.check.fine_frequency[0])
                hi = min(ra.check.fine_frequency[-1], rb.check.fine_frequency[-1])
                f, c = coherence(ra.acc_g, rb.acc_g, fs=1.0 / self.dt, nperseg=min(nper, len(ra.acc_g)))
                band = (f >= lo) & (f <= hi)
                out[f"{a}_{b}"] = {"mean": float(np.mean(c[band])), "max": float(np.max(c[band])),
                                   "band_hz": [float(lo), float(hi)], "segment_s": nper * self.dt}
        return out

    @property
    def correlation(self) -> float | None:
        """Pearson's correlation coefficient of the two axes' accelerations (None with one axis);
        with three axes, that of the pair that correlates most."""
        c = self.correlations
        return max(c.values(), key=abs) if c else None

    @property
    def ok(self) -> bool:
        c = self.correlation
        return all(r.ok for r in self.records.values()) and (c is None or abs(c) < MAX_CORRELATION)


#: AC156: the components must be statistically independent, correlation coefficient below this
MAX_CORRELATION = 0.3


def motion_problems(rrs: dict[str, RRS], duration: float, dt: float, strong: float | None,
                    standard: str | None, keys: dict[str, str]) -> list[str]:
    """What is wrong with a request for motions, one line each, ``keys`` naming the options."""
    problems = []
    if not (dt > 0 and math.isfinite(dt)):
        problems.append(f"{keys['dt']}: {dt:g} s must be positive")
    if not (duration > 0 and math.isfinite(duration)):
        problems.append(f"{keys['duration']}: {duration:g} s must be positive")
    if problems:
        return problems
    if duration / dt > 2e6:
        problems.append(f"{keys['duration']}, {keys['dt']}: {duration:g} s at {dt:g} s is {duration / dt:.3g} samples; "
                        f"at most 2e6 (a coarser {keys['dt']} or a shorter {keys['duration']})")
    top = max(r.check_range[1] for r in rrs.values())
    if top > MAX_CHECK_FRACTION / dt:
        problems.append(f"{keys['dt']}: {dt:g} s samples at {1 / dt:.4g} Hz, too coarse to carry the RRS up to "
                        f"{top:.4g} Hz: {keys['dt']} {MAX_CHECK_FRACTION / top:.3g} or finer carries it")
    low = min(r.check_range[0] for r in rrs.values())
    if duration < 8.0 / low:
        problems.append(f"{keys['duration']}: {duration:g} s holds only {duration * low:.3g} cycles of the lowest "
                        f"checked frequency ({low:.4g} Hz): at least {8.0 / low:.3g} s")
    s = default_strong(duration) if strong is None else strong
    if standard == "ac156" and (duration < AC156_DURATION or s < AC156_STRONG):
        problems.append(f"{keys['duration']}: {duration:g} s: AC156 asks for {AC156_STRONG:g} s of strong motion "
                        f"within at least {AC156_DURATION:g} s (ramps of 5 s): {keys['duration']} 30 or more")
    if standard == "ieee693" and s < IEEE693_STRONG:
        problems.append(f"{keys['duration']}: {duration:g} s: IEEE 693 asks for {IEEE693_STRONG:g} s of strong "
                        f"motion (ramps of 5 s): {keys['duration']} {IEEE693_DURATION:g} or more")
    return problems


def make_motions(rrs: dict[str, RRS], count: int, duration: float, dt: float, seed: int,
                 strong: float | None = None, progress=None, vertical: str = "x2", table=None) -> list[Motion]:
    """``count`` motions, each a record per axis of ``rrs``, matched to it; ``vertical``: the
    vertical axis (x2 in the plane, x3 in space); ``table``: a table.Table whose limits every
    record keeps within. An AnalysisError (what would work said) when one cannot be matched."""
    strong = default_strong(duration) if strong is None else strong
    motions = []
    for k in range(1, count + 1):
        m = _matched_motion(rrs, k, duration, dt, seed, strong, vertical, table)
        if not m.ok:
            raise AnalysisError(_failure(m, rrs, duration, dt, seed, strong, table))
        motions.append(m)
        if progress is not None:
            progress(k, count)
    return motions


def streams(axes, vertical: str = "x2") -> dict[str, int]:
    """Each axis's noise stream: 1 for x1, 2 for the vertical, 3 for the other horizontal (x2 of a
    deck in space), so that a deck in space gets the plane's x1 and vertical records, and its x2
    a record of its own."""
    out = {}
    for axis in axes:
        out[axis] = 1 if axis == "x1" else 2 if axis == vertical else 3
    return out


def _matched_motion(rrs, number, duration, dt, seed, strong, vertical: str = "x2", table=None) -> Motion:
    m = Motion(number, seed, dt, duration, strong, vertical=vertical)
    stream = streams(rrs, vertical)
    for axis, r in rrs.items():
        m.records[axis] = _within_table(r, axis, duration, dt, strong, (seed, number, stream[axis]), table)
    return m


#: a record short of its strong motion is made again on a longer plateau, at most this often
STRONG_TRIES = 3


def _within_table(r: RRS, axis: str, duration: float, dt: float, plateau: float, noise: tuple, table) -> Record:
    """A record of one axis within the table's limits (rbhyst.analyses.qualification.table): its
    high-pass raised step by step until it fits; the one that comes nearest where none does."""
    from rbhyst.analyses.qualification.table import HIGH_PASS_STEPS, MARGIN as TABLE_MARGIN

    if table is None:
        return _matched_record(r, axis, duration, dt, plateau, noise)
    cap = None if table.acceleration is None else table.acceleration * G * (1.0 - 2.0 * TABLE_MARGIN)
    best, best_excess = None, math.inf
    for hp in HIGH_PASS_STEPS:
        rec = _matched_record(r, axis, duration, dt, plateau, noise, hp, cap)
        rec.table, rec.reached = table, table.reached(rec.acc_g * G, dt)
        if rec.ok:
            return rec
        excess = max([rec.reached[k] / getattr(table, k) for k in table.over(rec.reached)], default=1.0)
        if rec.check.ok and rec.strong_ok and excess < best_excess:
            best, best_excess = rec, excess
    return best if best is not None else rec


def _matched_record(r: RRS, axis: str, duration: float, dt: float, plateau: float, noise: tuple,
                    high_pass: float = 0.5, peak_max: float | None = None) -> Record:
    """A record of one axis, its envelope's plateau lengthened (the same noise) until its
    strong motion, measured, holds what the RRS asks (``strong_min_s``) where it can."""
    for _ in range(STRONG_TRIES):
        acc, iterations = match(r, duration, dt, plateau, np.random.default_rng(list(noise)), high_pass, peak_max)
        acc_g = in_file_digits(acc / G)
        rec = Record(axis, acc_g, check_record(acc_g * G, dt, r), iterations,
                     strong_motion.measured(acc_g * G, dt), r.strong_min_s, plateau,
                     high_pass=high_pass * r.check_range[0])
        longest = duration - 1.0  # ramps of half a second at least
        if rec.strong_ok or plateau >= longest:
            return rec
        plateau = min(longest, plateau + (rec.strong_min - rec.strong) + 0.5)
    return rec


def _table_failure(axis: str, r: Record) -> str:
    """Which table limit a record is beyond at the least, and what would fit."""
    from rbhyst.analyses.qualification.table import said

    over = r.table.over(r.reached)
    parts = [f"the table's {k} limit is {said(k, getattr(r.table, k))} and the record asks {said(k, r.reached[k])}"
             for k in over]
    fit = ", ".join(f"{k}={1.05 * r.reached[k]:.3g}" for k in over)
    return (f"{axis}: {'; '.join(parts)} at the least (high-pass from {r.high_pass:.3g} Hz, the TRS in its band): "
            f"a table of {fit} would fit, or a smaller RRS")


def _failure(m: Motion, rrs, duration, dt, seed, strong, table=None) -> str:
    """Why motion ``m`` fails, and what would work: another seed tried here, or a longer motion."""
    bad = [f"{axis}: its TRS lies from {r.check.said()}, outside {r.check.band[0]:g}-{r.check.band[1]:g}"
           for axis, r in m.records.items() if not r.check.in_band]
    bad += [f"{axis}: {r.check.said_peak()}" for axis, r in m.records.items() if not r.check.peak_ok]
    bad += [_table_failure(axis, r) for axis, r in m.records.items() if not r.table_ok]
    bad += [f"{axis}: its strong motion lasts {r.strong:.3g} s, short of {r.strong_min:g} s ({strong_motion.DEFINITION})"
            for axis, r in m.records.items() if not r.strong_ok]
    pairs = m.correlations
    if len(pairs) == 1:
        c = m.correlation
        if abs(c) >= MAX_CORRELATION:
            bad.append(f"the axes' correlation coefficient is {c:.3f}, not below {MAX_CORRELATION:g}")
    else:
        bad += [f"the correlation coefficient of {pair.replace('_', ' and ')} is {c:.3f}, not below "
                f"{MAX_CORRELATION:g}" for pair, c in pairs.items() if abs(c) >= MAX_CORRELATION]
    if all(r.check.ok and r.strong_ok for r in m.records.values()) and \
            all(abs(c) < MAX_CORRELATION for c in m.correlations.values()):
        # matched, but beyond the table: what would fit is said with each record
        return f"motion {m.number} (seed {seed}) cannot be made within the table: {'; '.join(bad)}"
    works = None
    for other in range(seed + 1, seed + 4):
        if _matched_motion(rrs, m.number, duration, dt, other, strong, m.vertical, table).ok:
            works = f"--seed {other} meets it"
            break
    if works is None:
        works = f"a longer --duration ({1.5 * duration:.3g} s) or a finer --dt ({dt / 2:g} s) may"
    return f"motion {m.number} (seed {seed}) cannot be matched after {MAX_ITERATIONS} iterations: " \
           f"{'; '.join(bad)}; {works}"


def _taper(f: np.ndarray, f_low: float, f_high: float) -> np.ndarray:
    """A smooth band-pass: 0 below f_low / 2, a raised cosine in log f up to f_low, 1 to f_high,
    a raised cosine down to 0 at f_high x 1.25."""
    out = np.ones_like(f)
    with np.errstate(divide="ignore"):
        lf = np.log2(np.where(f > 0, f, 1e-300) / f_low)
    out[lf <= -1.0] = 0.0
    rise = (lf > -1.0) & (lf < 0.0)
    out[rise] = np.sin(0.5 * np.pi * (lf[rise] + 1.0)) ** 2
    x = np.log2(np.where(f > 0, f, 1e-300) / f_high) / math.log2(1.25)
    out[x >= 1.0] = 0.0
    fall = (x > 0.0) & (x < 1.0)
    out[fall] = np.cos(0.5 * np.pi * x[fall]) ** 2
    return out


def aims(band: tuple[float, float]) -> tuple[float, float, float]:
    """AIM, TOP_AIM and PEAK_FLOOR for a band: as set for AC156's 0.9-1.3 (the middle of the band
    in logarithm; the top's aim and the peaks' floor scaled with the band's lower limit)."""
    lo, hi = band
    scale = lo / 0.9
    return math.sqrt(lo * hi), TOP_AIM * scale, PEAK_FLOOR * scale


def _lift(acc: np.ndarray, pulse: np.ndarray, target: float) -> np.ndarray:
    """acc with its largest peak raised to ``target`` by a pulse centred on it (``pulse``: the
    process's autocorrelation, 1 at its first sample)."""
    i = int(np.argmax(np.abs(acc)))
    n = len(acc)
    return acc + np.sign(acc[i]) * (target - abs(acc[i])) * np.roll(pulse, i)[:n]


def match(rrs: RRS, duration: float, dt: float, strong: float, rng,
          high_pass: float = 0.5, peak_max: float | None = None) -> tuple[np.ndarray, int]:
    """One record (m/s2) whose TRS lies within the RRS's band and whose peak acceleration is at
    least the RRS's ``peak_min`` (as far as MAX_ITERATIONS take it), and the iterations it took.

    Long because it is one iteration loop with its set-up: the control frequencies and aims, the
    band, the Fourier correction, the peaks cut or raised and the end at rest."""
    n = int(round(duration / dt)) + 1
    t = dt * np.arange(n)
    env = envelope(t, duration, strong)
    # the filtering below smears a little of the record onto its first and last samples: a
    # half-second taper (where the envelope is below 3 %) brings them back to exactly zero
    edges = envelope(t, duration, duration - 2.0 * min(0.5, 0.5 * (duration - strong)))
    lo, hi = rrs.check_range
    # zero padding: the corrections act as filters a few periods of the lowest frequency long,
    # whose tails must not wrap around onto the record's other end
    m = n + int(math.ceil(4.0 / (0.5 * lo) / dt))
    f = np.fft.rfftfreq(m, dt)
    top = min(hi * 1.25, 0.4 / dt)
    checks = fine_grid(lo, hi)  # the band is met on the fine grid, the standard's points among it
    control = np.unique(np.concatenate([lo / 2.0 * 2.0 ** (np.arange(int(12 * math.log2(2 * top / lo)) + 1) / 12.0),
                                        checks]))
    # at the top of the range the TRS tends to the peak acceleration, which the content below
    # sets as much as the content there: aimed lower there, it lands inside the band
    aim_mid, aim_top, peak_floor = aims(rrs.band)
    aim = rrs(control) * np.exp(np.interp(np.log(control), np.log([hi / 4.0, hi]), [math.log(aim_mid),
                                                                                    math.log(aim_top)]))
    is_check = np.isin(control, checks)
    top_check = np.flatnonzero(is_check)[-1]
    lf = np.log(np.maximum(f, 1e-6))
    band = _taper(f, high_pass * lo, min(top * 1.2, 0.8 * 0.5 / dt))
    amp = rrs(np.maximum(f, 1e-6)) * band
    acc = to_rest(env * np.fft.irfft(np.fft.rfft(rng.standard_normal(m)) * amp, m)[:n], dt, env)
    lo_ok, hi_ok = rrs.band[0] + MARGIN, rrs.band[1] - 3 * MARGIN
    # the least peak acceleration (when the RRS asks for one), with the same margin, and what a
    # peak below it is raised to
    peak_ok = None if rrs.peak_min is None else rrs.peak_min * (1.0 + MARGIN)
    pulse = None
    if peak_ok is not None:
        # the shape a peak of the process has on average: given x(t0) = a, a Gaussian process is
        # a rho(t - t0) in the mean, rho its autocorrelation, the transform of its power spectrum
        pulse = np.fft.irfft(amp**2, m)
        pulse /= pulse[0]
    best, best_err, best_it = None, math.inf, 0
    for it in range(MAX_ITERATIONS + 1):
        sa = trs(acc, dt, control, rrs.damping)
        ratio = sa / rrs(control)
        r_check = ratio[is_check]
        err = max(np.max(np.log(lo_ok / r_check)), np.max(np.log(r_check / hi_ok)))
        if peak_ok is not None:
            err = max(err, math.log(peak_ok / np.max(np.abs(acc))))
        if peak_max is not None:  # a table's limit
            err = max(err, math.log(np.max(np.abs(acc)) / peak_max))
        if err < best_err:
            best, best_err, best_it = acc, err, it
        if err <= 0.0 or it == MAX_ITERATIONS:
            break
        # Fourier amplitudes times aim / TRS, interpolated on log frequency (flat beyond the
        # control frequencies), at most doubled or halved at once, and band-limited again (the
        # end-at-rest correction and the cut peaks below leave content outside the band)
        correction = np.exp(np.interp(lf, np.log(control), np.log(aim / sa)))
        acc = np.fft.irfft(np.fft.rfft(acc, m) * np.clip(correction, 0.5, 2.0) * band, m)[:n]
        if ratio[top_check] > hi_ok:
            # where the TRS at the top, the peak acceleration, is too high, the peaks are cut
            # to what it should be (the next corrections restore the spectrum around them), but
            # never below the RRS there: a rigid oscillator sees the peak acceleration itself
            limit = max(np.max(np.abs(acc)) * aim_top / ratio[top_check], peak_floor * rrs(hi),
                        0.0 if peak_ok is None else peak_ok * (1.0 + MARGIN))
            acc = np.clip(acc, -limit * env, limit * env)
        elif peak_ok is not None and np.max(np.abs(acc)) < peak_ok:
            # a peak below the least the RRS asks for is raised, by the process's own shape
            # of a peak (the next corrections restore the spectrum around it)
            acc = _lift(acc, pulse, peak_ok * (1.0 + MARGIN))
        if peak_max is not None and np.max(np.abs(acc)) > peak_max:
            acc = np.clip(acc, -peak_max, peak_max)  # the table's limit (the corrections restore the spectrum)
        acc = to_rest(acc * edges, dt, env)
    return best, best_it


# ---------------------------------------------------------------- files

#: trs.csv's columns, one row per motion, axis and checked frequency; the last three, the same on
#: every row of a motion's axis, its peak acceleration, the least it may be (empty: not checked)
#: and whether it is (yes, no; empty: not checked)
TRS_COLUMNS = ("motion", "axis", "frequency_hz", "rrs_g", "trs_g", "ratio", "lower_g", "upper_g", "within",
               "peak_g", "peak_min_g", "peak_within")


def record_text(motion: Motion, axis: str, mark: str) -> str:
    """A record file as make-record writes one: its mark line, ``time_s,acceleration_g``, rows."""
    import io

    what = "vertical" if axis == motion.vertical else "horizontal"
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([motion.time, motion.records[axis].acc_g]), delimiter=",", comments="",
               fmt="%.6f," + FILE_FORMAT,
               header=f"{mark}: motion {motion.number}, {axis} ({what})\ntime_s,acceleration_g")
    return buf.getvalue()


def record_name(motion: Motion, axis: str) -> str:
    return f"m{motion.number}_{axis}.csv"


def trs_rows(motions: list[Motion], fine: bool = False) -> list[str]:
    """trs.csv's lines (TRS_COLUMNS): a row per motion, axis and 1/6-octave point of the check
    range; ``fine``: trs_fine.csv's, the same columns on the fine grid."""
    lines = [",".join(TRS_COLUMNS)]
    for m in motions:
        for axis, r in m.records.items():
            c = r.check
            lo, hi = c.band
            peak = "" if c.peak is None else f"{c.peak / G:.6g}"
            least, ok_peak = ("", "") if c.peak_min is None else (f"{c.peak_min / G:.6g}",
                                                                  "yes" if c.peak_ok else "no")
            rows = (zip(c.fine_frequency, c.fine_rrs / G, c.fine_trs / G, c.fine_within) if fine else
                    zip(c.frequency_hz, c.rrs / G, c.trs / G, c.within))
            for f, a, b, ok in rows:
                lines.append(f"{m.number},{axis},{f:.6g},{a:.6g},{b:.6g},{b / a:.6g},{lo * a:.6g},{hi * a:.6g},"
                             f"{'yes' if ok else 'no'},{peak},{least},{ok_peak}")
    return lines


#: records.csv's columns, one row per motion and axis: what the record is, beside trs.csv
RECORD_COLUMNS = ("motion", "axis", "file", "pga_g", "pgv_m_s", "pgd_m", "displacement_peak_to_peak_m",
                  "strong_motion_s", "strong_motion_min_s", "strong_motion_within", "bracketed_25_s",
                  "arias_5_75_s", "arias_5_95_s")


def record_rows(motions: list[Motion]) -> list[str]:
    lines = [",".join(RECORD_COLUMNS)]
    for m in motions:
        for axis, r in m.records.items():
            v, d = integrate(r.acc_g * G, m.dt)
            least, ok = ("", "") if r.strong_min is None else (f"{r.strong_min:g}", "yes" if r.strong_ok else "no")
            lines.append(",".join([str(m.number), axis, record_name(m, axis), f"{np.max(np.abs(r.acc_g)):.6g}",
                                   f"{np.max(np.abs(v)):.6g}", f"{np.max(np.abs(d)):.6g}", f"{np.ptp(d):.6g}",
                                   f"{r.strong:.4f}", least, ok, f"{r.durations['bracketed_25_s']:.4f}",
                                   f"{r.durations['arias_5_75_s']:.4f}", f"{r.durations['arias_5_95_s']:.4f}"]))
    return lines


def write_tables(folder, motions: list[Motion]) -> None:
    """trs.csv (the standard's points), trs_fine.csv (the fine grid) and records.csv (each
    record's peaks and strong motion) into ``folder``."""
    from pathlib import Path

    for name, lines in (("trs.csv", trs_rows(motions)), ("trs_fine.csv", trs_rows(motions, True)),
                        ("records.csv", record_rows(motions))):
        (Path(folder) / name).write_text("\n".join(lines) + "\n", encoding="utf-8")


def motions_summary(motions: list[Motion], rrs: dict[str, RRS], standard: str | None) -> dict:
    """motions.json: the method, the RRS and, per motion and axis, what the record is."""
    from rbhyst._version import __version__

    return {
        "rbhyst_version": __version__,
        "method": "envelope-shaped band-limited Gaussian noise (PCG64), Fourier amplitudes iterated by "
                  "aim / TRS at 1/12-octave control frequencies and the 1/48-octave grid of the check range "
                  "until the TRS lies within the band at every frequency of that grid (the standard's "
                  "1/6-octave points among them); corrected to end at rest (final velocity and displacement zero "
                  "for the record linear between its samples)",
        "aim": {"ratio": AIM, "at_top_of_range": TOP_AIM},
        "standard": standard,
        "rrs": {axis: r.describe() for axis, r in rrs.items()},
        "motions": [{"number": m.number, "seed": m.seed, "dt_s": m.dt, "duration_s": m.duration,
                     # the least of its axes', each measured as the standards define it
                     "strong_motion_s": min(r.strong for r in m.records.values()),
                     "correlation_x1_x2": m.correlation if len(m.records) < 3 else m.correlations["x1_x2"],
                     **({"correlations": m.correlations} if len(m.records) > 2 else {}),
                     "coherence": m.coherences(),
                     "files": {axis: record_name(m, axis) for axis in m.records},
                     "axes": {axis: r.facts(m.dt, rrs[axis]) for axis, r in m.records.items()}}
                    for m in motions],
    }
