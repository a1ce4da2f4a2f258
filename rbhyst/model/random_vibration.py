"""Random vibration: a stationary Gaussian support acceleration with a given power spectral density
(its check against the PSD, the Welch estimate, is in rbhyst.analyses.qualification.psd).

A PSD is given as breakpoints (frequency in Hz, value in g2/Hz or (m/s2)2/Hz), straight lines
between them on log-log axes, as MIL-STD-810 tables give them, and zero outside them. The
history is a sum of sinusoids at every frequency k / T of the FFT grid of its duration T, each
of amplitude sqrt(2 PSD(f_k) df) and of a phase drawn uniformly from numpy's PCG64
(``default_rng(seed)``, the same numbers on every machine), then scaled so that its mean square
is exactly the PSD's integral (the exact integral of the power-law pieces): stationary over its
whole length (the inverse FFT is periodic in T: no start-up), Gaussian by the central limit
theorem over its thousands of components, with exactly the asked-for periodogram. It is made
once into samples at ``dt`` (default a tenth of the period of the PSD's highest frequency) and
from then on is a record like any other: linear between its samples, zero after them.
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


def random_history(psd: PSD, duration: float, seed: int, dt: float | None = None) -> tuple[float, np.ndarray]:
    """(dt, samples in m/s2) of a stationary Gaussian history with the PSD, ``duration`` s long."""
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
    return step, x


@functools.lru_cache(maxsize=8)
def cached_history(psd_key: tuple, duration: float, seed: int, dt: float | None) -> tuple[float, np.ndarray]:
    """random_history, made once per process for the same PSD, duration, seed and dt."""
    f, v = psd_key
    step, x = random_history(PSD(np.array(f), np.array(v)), duration, seed, dt)
    x.flags.writeable = False  # shared by every run that asks for it
    return step, x
