"""The check of random vibration against its PSD: the Welch estimate averaged over each band
between the PSD's breakpoints, and the rms (the history itself is made in
rbhyst.model.random_vibration)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.model.random_vibration import G, PSD, load_psd, random_history  # noqa: F401 (the API of random vibration)


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


def welch_check(x: np.ndarray, dt: float, psd: PSD) -> tuple[list[BandCheck], float, float]:
    """The Welch PSD of ``x`` (Hann windows, half overlap, at least 8 bins in the lowest band)
    averaged over each band between breakpoints against the target's average over the same
    bins, and the rms of ``x`` and of the PSD."""
    from scipy.signal import welch

    narrowest = float(np.min(np.diff(psd.frequency_hz)))
    nper = 2 ** int(math.ceil(math.log2(8.0 / (narrowest * dt))))
    nper = min(nper, len(x))
    f, pxx = welch(x, fs=1.0 / dt, window="hann", nperseg=nper, noverlap=nper // 2, detrend=False)
    res = f[1] - f[0]
    out = []
    for a, b in zip(psd.frequency_hz[:-1], psd.frequency_hz[1:]):
        # the outermost bins of the whole PSD hold half their power (the Hann window's width):
        # a bin is counted one resolution inside the PSD's ends
        lo = a + (res if a == psd.frequency_hz[0] else 0.0)
        hi = b - (res if b == psd.frequency_hz[-1] else 0.0)
        sel = (f >= lo) & (f <= hi)
        out.append(BandCheck(float(a), float(b), float(pxx[sel].mean()) if sel.any() else 0.0,
                             float(psd(f[sel]).mean()) if sel.any() else 0.0, int(sel.sum())))
    return out, float(np.sqrt(np.mean(x * x))), psd.rms
