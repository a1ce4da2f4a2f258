"""Top layer: the documented import paths of response spectra (``rbhyst.response``,
``rbhyst.response.record``, ``.transmissibility``, ``.ground``), kept for scripts; the code
lives in :mod:`rbhyst.solve.spectra` and :mod:`rbhyst.analyses`.

The names below are loaded on first use (PEP 562), so that a run which asks for no spectra
never imports their compiled kernels (and with them numba).
"""

from __future__ import annotations

import importlib

__all__ = ["Spectrum", "SpectrumAccumulator", "default_periods", "response_spectrum", "step_coefficients"]


def __getattr__(name: str):
    if name in __all__:
        return getattr(importlib.import_module("rbhyst.solve.spectra"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
