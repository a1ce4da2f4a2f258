"""Random vibration: a Gaussian support acceleration with a given power spectral density, as a
vibration controller drives a shaker, and its check against the standard's tolerances.

A PSD is given as breakpoints (frequency in Hz, value in g2/Hz or (m/s2)2/Hz), straight lines
between them on log-log axes, as MIL-STD-810 tables give them, and zero outside them. The
stationary history is a sum of sinusoids at every frequency k / T of the FFT grid of its
duration T, each of amplitude sqrt(2 PSD(f_k) df) and of a phase drawn uniformly from numpy's
PCG64 (``default_rng(seed)``, the same numbers on every machine), scaled so that its mean
square is exactly the PSD's integral (the exact integral of the power-law pieces): Gaussian by
the central limit theorem over its thousands of components, with exactly the asked-for
periodogram, and nothing below the PSD's lowest frequency (its high-pass). Optionally its peaks
are limited to ``clip_sigma`` times its rms (a controller's sigma clipping; 3 is usual). Then,
as a controller starts and stops a shaker, it rises over a start-up ramp and falls over a
shut-down ramp (raised cosines, ``ramp`` s each), and is corrected to end at rest
(rbhyst.model.baseline.to_rest): it starts and ends with acceleration, velocity and
displacement zero, its drive displacement bounded by its content (the sum alone drifts: its
velocity starts from the sum of its components' initial values). It is made once into samples at
``dt`` (default a tenth of the period of the PSD's highest frequency) and from then on is a
record like any other: linear between its samples, zero after them.

The check (``tolerance``) is MIL-STD-810H Method 514.8's for a random vibration test: the PSD
measured at full level (between the ramps; Welch's estimate, Hann windows, half overlap) within
+-3 dB of the target at every spectral line below 500 Hz and +-6 dB above, each band's rms (the
bands between breakpoints) and the overall rms within 10 % of the target's, the estimate having
at least 120 statistical degrees of freedom (a shorter history is said to be too short to check).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.files.curves import read_curve

G = 9.80665

#: the units a PSD may be given in, and their factor to (m/s2)2/Hz
PSD_UNITS = {"g2/Hz": G * G, "(m/s2)2/Hz": 1.0}
#: at most this many samples are held (8 bytes each, and the FFT's complex twice that)
MAX_SAMPLES = 20_000_000
#: default samples per period of the PSD's highest frequency (linear interpolation between
#: samples then passes 95 % of the power there: sinc(0.1)^4)
SAMPLES_PER_PERIOD = 10


@dataclass(frozen=True)
class PSD:
    """Breakpoints ``frequency_hz`` (ascending) and ``value`` ((m/s2)2/Hz), log-log between them."""

    frequency_hz: np.ndarray
    value: np.ndarray

    def __call__(self, f) -> np.ndarray:
        f = np.asarray(f, float)
        inside = (f >= self.frequency_hz[0]) & (f <= self.frequency_hz[-1])
        out = np.zeros(f.shape)
        lf = np.log(f[inside])
        out[inside] = np.exp(np.interp(lf, np.log(self.frequency_hz), np.log(self.value)))
        return out

    def band_power(self) -> np.ndarray:
        """The exact integral of each power-law piece between two breakpoints ((m/s2)2)."""
        f1, f2 = self.frequency_hz[:-1], self.frequency_hz[1:]
        p1, p2 = self.value[:-1], self.value[1:]
        slope = np.log(p2 / p1) / np.log(f2 / f1)
        with np.errstate(divide="ignore", invalid="ignore"):
            general = p1 * f1 / (slope + 1.0) * ((f2 / f1) ** (slope + 1.0) - 1.0)
        return np.where(np.abs(slope + 1.0) < 1e-12, p1 * f1 * np.log(f2 / f1), general)

    @property
    def rms(self) -> float:
        """sqrt of the integral of the PSD (m/s2)."""
        return math.sqrt(float(self.band_power().sum()))


def psd_problems(points) -> list[tuple[int | None, str]]:
    """What is wrong with a list of [frequency_hz, value] breakpoints: (0-based index or None, message)."""
    if not isinstance(points, list) or len(points) < 2:
        return [(None, "at least two [frequency_hz, value] breakpoints")]
    problems, previous = [], None
    for k, p in enumerate(points):
        if not (isinstance(p, (list, tuple)) and len(p) == 2 and all(isinstance(x, (int, float)) and not
                                                                     isinstance(x, bool) for x in p)):
            problems.append((k, "must be [frequency_hz, value]"))
            previous = None
            continue
        if not (p[0] > 0 and p[1] > 0 and math.isfinite(p[0]) and math.isfinite(p[1])):
            problems.append((k, "the frequency and the value must be positive (log-log interpolation)"))
        elif previous is not None and p[0] <= previous:
            problems.append((k, f"the frequency {p[0]:g} Hz does not increase (the breakpoint before is at "
                                f"{previous:g} Hz)"))
        previous = p[0]
    return problems


#: how a PSD file's value column may declare its unit (compacted, lower case)
_PSD_SPELLINGS = {"g2/hz": "g2/Hz", "g^2/hz": "g2/Hz", "g2_hz": "g2/Hz", "g2hz": "g2/Hz", "g2perhz": "g2/Hz",
                  "(m/s2)2/hz": "(m/s2)2/Hz", "(m/s^2)^2/hz": "(m/s2)2/Hz", "m2/s4/hz": "(m/s2)2/Hz",
                  "m2_s4_hz": "(m/s2)2/Hz", "(m/s2)^2/hz": "(m/s2)2/Hz"}


def _declared_psd_unit(label: str) -> tuple[str | None, str | None]:
    """(token, unit) a PSD column label declares: 'psd_g2_hz', 'asd [g^2/Hz]', 'psd (m/s2)2/Hz'."""
    text = label.strip()
    if "[" in text and text.endswith("]"):
        token = text[text.rindex("[") + 1:-1]
    elif text.endswith(")") and "(" in text and not text.endswith("2/Hz)"):
        token = text[text.rindex("(") + 1:-1]
    else:
        low = text.lower().replace(" ", "")
        for spelling in sorted(_PSD_SPELLINGS, key=len, reverse=True):
            if low.endswith(spelling) and (len(low) == len(spelling) or low[-len(spelling) - 1] in "_ "):
                return spelling, _PSD_SPELLINGS[spelling]
        return None, None
    return token, _PSD_SPELLINGS.get(token.lower().replace(" ", ""))


def load_psd(psd, units: str, base: Path) -> PSD:
    """A PSD from breakpoints or a file (relative to ``base``), in SI."""
    factor = PSD_UNITS[units]
    if isinstance(psd, str):
        path = Path(psd) if Path(psd).is_absolute() else base / psd
        curve = read_curve(path, "a PSD")
        if curve.header_line is not None and len(curve.labels) == 2:
            token, unit = _declared_psd_unit(curve.labels[1])
            if token is not None and unit is None:
                raise InputError(f"{path}:{curve.header_line}: the value column {curve.labels[1]!r}: {token!r} is "
                                 f"not a PSD unit rbhyst knows ({', '.join(PSD_UNITS)})")
            if unit is not None and unit != units:
                raise InputError(f"{path}:{curve.header_line}: the header declares {curve.labels[1]!r} ({unit}) "
                                 f'but the deck says units = "{units}"')
        return PSD(curve.x, curve.y * factor)
    data = np.array(psd, float)
    return PSD(data[:, 0], data[:, 1] * factor)


def sample_step(psd: PSD, dt: float | None) -> float:
    return dt if dt is not None else 1.0 / (SAMPLES_PER_PERIOD * float(psd.frequency_hz[-1]))


def size_problems(psd: PSD, duration: float, dt: float | None, where: str) -> list[str]:
    """A history that would not carry the PSD, or not fit in memory."""
    step = sample_step(psd, dt)
    top = float(psd.frequency_hz[-1])
    problems = []
    if step > 0.4 / top:
        problems.append(f"{where}.dt: {step:g} s samples at {1 / step:.4g} Hz, too coarse for the PSD's "
                        f"{top:.4g} Hz: at most {0.4 / top:.3g} s (2.5 samples a period), "
                        f"{1 / (SAMPLES_PER_PERIOD * top):.3g} s by default")
    n = duration / step
    if n > MAX_SAMPLES:
        problems.append(f"{where}.duration: {duration:g} s at {step:g} s is {n:.3g} samples; rbhyst holds at most "
                        f"{MAX_SAMPLES:.0e} ({MAX_SAMPLES * 8 / 1e6:.0f} MB): {MAX_SAMPLES * step:.4g} s at most "
                        f"(or a larger {where}.dt)")
    if duration * float(psd.frequency_hz[0]) < 4.0:
        problems.append(f"{where}.duration: {duration:g} s holds {duration * psd.frequency_hz[0]:.3g} cycles of the "
                        f"PSD's lowest frequency ({psd.frequency_hz[0]:.4g} Hz): at least "
                        f"{4.0 / psd.frequency_hz[0]:.3g} s")
    return problems


#: MIL-STD-810H Method 514.8: the measured PSD within +-3 dB of the target at each line below
#: 500 Hz and +-6 dB above; the rms (overall and of each band) within 10 %
LINE_TOLERANCE_DB = ((500.0, 3.0), (math.inf, 6.0))
RMS_TOLERANCE = 0.10
#: ... estimated with at least this many statistical degrees of freedom (the standard's minimum
#: for the control analysis)
MIN_DOF = 120
#: sigma clipping: the peaks within (1 + CLIP_EXCESS) x the limit after at most CLIP_PASSES
#: corrections to rest
CLIP_PASSES, CLIP_EXCESS = 5, 1e-6
#: the start-up and shut-down ramps, s (None in a deck: this, at most a tenth of the duration)
DEFAULT_RAMP_S = 2.0


def default_ramp(duration: float) -> float:
    return min(DEFAULT_RAMP_S, 0.1 * duration)


def ramps(n: int, dt: float, ramp: float) -> np.ndarray:
    """1 between a raised-cosine rise over the first ``ramp`` s and a fall over the last."""
    t = dt * np.arange(n)
    e = np.ones(n)
    if ramp > 0.0:
        up, down = t < ramp, t > t[-1] - ramp
        e[up] = np.sin(0.5 * np.pi * t[up] / ramp) ** 2
        e[down] = np.sin(0.5 * np.pi * (t[-1] - t[down]) / ramp) ** 2
    return e


def random_history(psd: PSD, duration: float, seed: int, dt: float | None = None, ramp: float | None = None,
                   clip_sigma: float | None = None) -> tuple[float, np.ndarray]:
    """(dt, samples in m/s2) of the history with the PSD, ``duration`` s long: stationary between
    its ramps (``ramp`` s, default_ramp by default; 0: none and no correction to rest), its peaks
    limited to ``clip_sigma`` rms where given, at rest at both ends."""
    step = sample_step(psd, dt)
    n = int(round(duration / step))
    n += n % 2  # an even length: every component but the mean has its conjugate pair
    df = 1.0 / (n * step)
    f = np.arange(n // 2 + 1) * df
    amp = np.sqrt(2.0 * psd(f) * df)  # each component's amplitude: mean square amp^2 / 2
    amp[0] = amp[-1] = 0.0
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, len(f))
    x = np.fft.irfft(amp * np.exp(1j * phase) * (n / 2.0), n)
    ms = float(np.mean(x * x))
    if ms > 0.0:
        x *= psd.rms / math.sqrt(ms)  # the sum over the grid to the exact integral
    limit = None if clip_sigma is None else clip_sigma * psd.rms
    if limit is not None:
        x = np.clip(x, -limit, limit)
    r = default_ramp(duration) if ramp is None else ramp
    if r > 0.0:
        from rbhyst.model.baseline import to_rest

        env = ramps(n, step, r)
        x = to_rest(x * env, step, env)
        # the correction to rest is smooth and small; where it lifts a clipped peak, clip again
        for _ in range(CLIP_PASSES if limit is not None else 0):
            if np.max(np.abs(x)) <= limit * (1.0 + CLIP_EXCESS):
                break
            x = to_rest(np.clip(x, -limit, limit), step, env)
    return step, x


@functools.lru_cache(maxsize=8)
def cached_history(psd_key: tuple, duration: float, seed: int, dt: float | None, ramp: float | None = None,
                   clip_sigma: float | None = None) -> tuple[float, np.ndarray]:
    """random_history, made once per process for the same PSD, duration, seed, dt, ramp and clip."""
    f, v = psd_key
    step, x = random_history(PSD(np.array(f), np.array(v)), duration, seed, dt, ramp, clip_sigma)
    x.flags.writeable = False  # shared by every run that asks for it
    return step, x


# ---------------------------------------------------------------- the check


@dataclass(frozen=True)
class BandCheck:
    f_lo: float
    f_hi: float
    measured: float  # mean Welch PSD over the band's bins, (m/s2)2/Hz
    target: float
    bins: int

    @property
    def db(self) -> float:
        return 10.0 * math.log10(self.measured / self.target)


def _welch(x: np.ndarray, dt: float, psd: PSD):
    """Welch's PSD of ``x`` (Hann windows, half overlap, at least 8 bins in the narrowest band)."""
    from scipy.signal import welch

    narrowest = float(np.min(np.diff(psd.frequency_hz)))
    nper = min(2 ** int(math.ceil(math.log2(8.0 / (narrowest * dt)))), len(x))
    return welch(x, fs=1.0 / dt, window="hann", nperseg=nper, noverlap=nper // 2, detrend=False)


def _bands(f: np.ndarray, psd: PSD):
    """Each band's bins: the outermost bins of the whole PSD hold half their power (the Hann
    window's width), so a bin counts one resolution inside the PSD's ends."""
    res = f[1] - f[0]
    for a, b in zip(psd.frequency_hz[:-1], psd.frequency_hz[1:]):
        lo = a + (res if a == psd.frequency_hz[0] else 0.0)
        hi = b - (res if b == psd.frequency_hz[-1] else 0.0)
        yield float(a), float(b), (f >= lo) & (f <= hi)


def welch_check(x: np.ndarray, dt: float, psd: PSD) -> tuple[list[BandCheck], float, float]:
    """The Welch PSD of ``x`` averaged over each band between breakpoints against the target's
    average over the same bins, and the rms of ``x`` and of the PSD."""
    f, pxx = _welch(x, dt, psd)
    out = [BandCheck(a, b, float(pxx[sel].mean()) if sel.any() else 0.0,
                     float(psd(f[sel]).mean()) if sel.any() else 0.0, int(sel.sum())) for a, b, sel in _bands(f, psd)]
    return out, float(np.sqrt(np.mean(x * x))), psd.rms


def tolerance(x: np.ndarray, dt: float, psd: PSD, ramp: float) -> dict:
    """MIL-STD-810H Method 514.8's check of the history at full level (between its ramps): every
    line's deviation against its limit, each band's rms and the overall rms against the target's."""
    k = int(math.ceil(ramp / dt))
    full = x[k:len(x) - k] if len(x) > 2 * k + 16 else x
    f, pxx = _welch(full, dt, psd)
    res = float(f[1] - f[0])
    nper = 2 * (len(f) - 1)
    dof = 2 * max(1, (len(full) - nper) // (nper // 2) + 1)  # 2 a segment, Hann at half overlap
    if dof < MIN_DOF:  # too short a history for the standard's estimate
        return {"standard": "MIL-STD-810H Method 514.8", "analysed_s": len(full) * dt, "resolution_hz": res,
                "dof": dof, "pass": None,
                "why": f"{len(full) * dt:.3g} s at full level give {dof} statistical degrees of freedom at "
                       f"{res:.3g} Hz resolution; the standard's estimate asks {MIN_DOF}: at least "
                       f"{(MIN_DOF / 2 + 1) * 0.5 / res:.3g} s"}
    lines = np.zeros(len(f), dtype=bool)
    bands = []
    for a, b, sel in _bands(f, psd):
        lines |= sel
        measured = math.sqrt(float(np.sum(pxx[sel])) * res)
        target = math.sqrt(float(np.sum(psd(f[sel]))) * res)
        bands.append({"from_hz": a, "to_hz": b, "rms_m_s2": measured, "target_m_s2": target,
                      "ratio": measured / target if target > 0 else None,
                      "pass": target > 0 and abs(measured / target - 1.0) <= RMS_TOLERANCE})
    with np.errstate(divide="ignore"):
        db = 10.0 * np.log10(pxx[lines] / psd(f[lines]))
    limit = np.array([next(lim for top, lim in LINE_TOLERANCE_DB if x_ < top) for x_ in f[lines]])
    outside = np.abs(db) > limit
    rms = float(np.sqrt(np.mean(full * full)))
    worst = int(np.argmax(np.abs(db) - limit)) if len(db) else None
    return {"standard": "MIL-STD-810H Method 514.8",
            "rule": "each line within +-3 dB below 500 Hz and +-6 dB above, each band's rms and the overall rms "
                    "within 10 %",
            "analysed_s": len(full) * dt, "resolution_hz": res, "dof": dof, "lines": int(len(db)),
            "lines_outside": int(outside.sum()),
            "worst_line_db": None if worst is None else float(db[worst]),
            "worst_line_hz": None if worst is None else float(f[lines][worst]),
            "bands": bands, "rms_m_s2": rms, "target_rms_m_s2": psd.rms,
            "rms_pass": abs(rms / psd.rms - 1.0) <= RMS_TOLERANCE,
            "pass": bool(not outside.any() and all(b["pass"] for b in bands)
                         and abs(rms / psd.rms - 1.0) <= RMS_TOLERANCE)}


def said(check: dict) -> str:
    """A line on the check."""
    if check["pass"] is None:
        return f"random vibration not checked against {check['standard']}: {check['why']}"
    verdict = "within" if check["pass"] else "NOT within"
    return (f"random vibration {verdict} the tolerances of {check['standard']} ({check['rule']}) at full level "
            f"({check['analysed_s']:.3g} s, {check['dof']} degrees of freedom): "
            f"{check['lines_outside']} of {check['lines']} lines outside, the worst {check['worst_line_db']:+.2f} dB "
            f"at {check['worst_line_hz']:.4g} Hz; rms {check['rms_m_s2'] / G:.4g} g against {check['target_rms_m_s2'] / G:.4g} g")
