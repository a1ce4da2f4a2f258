"""The compiled kernels a run calls: built ahead of time when they are current, else numba's JIT.

``kernel(name)`` gives the extension's function where ``rbhyst.kernels._aot`` was built at
install from the sources as they are now (rbhyst.kernels.aot), and otherwise the numba
dispatcher (compiled on first use and cached). Both run the same code to the bit; only the
first costs no numba import. ``RBHYST_JIT=1`` in the environment forces the JIT kernels.
"""

from __future__ import annotations

import functools
import importlib
import os


@functools.cache
def _aot():
    """The extension module, if it exists and was built from the sources as they are now."""
    if os.environ.get("RBHYST_JIT") or os.environ.get("NUMBA_DISABLE_JIT"):
        return None
    try:
        from . import _aot as module
        from .aot import source_stamp
    except ImportError:
        return None
    return module if module.stamp() == source_stamp() else None


def ahead_of_time() -> bool:
    """Whether the kernels come from the extension built at install."""
    return _aot() is not None


def kernel(name: str):
    """The callable for one of rbhyst.kernels.aot.EXPORTS."""
    module = _aot()
    if module is not None:
        return getattr(module, name)
    from .aot import EXPORTS

    mod, func, _ = EXPORTS[name]
    return getattr(importlib.import_module(mod), func)
