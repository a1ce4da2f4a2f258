"""The check of random vibration against its PSD: the Welch estimate averaged over each band
between the PSD's breakpoints, the rms, and MIL-STD-810H's tolerances (made and checked in
rbhyst.model.random_vibration, where the run's own check is made)."""

from rbhyst.model.random_vibration import (G, PSD, BandCheck, load_psd, random_history,  # noqa: F401 (the API)
                                           tolerance, welch_check)
