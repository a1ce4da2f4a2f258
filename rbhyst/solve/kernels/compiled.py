"""The compiled kernels a run calls: built ahead of time when they are current, else numba's JIT.

``kernel(name)`` gives the extension's function where ``rbhyst.solve.kernels._aot`` was built at
install from the sources as they are now (rbhyst.solve.kernels.aot), and otherwise the numba
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
        from rbhyst.solve.kernels import _aot as module
        from rbhyst.solve.kernels.aot import source_stamp
    except ImportError:
        return None
    return module if module.stamp() == source_stamp() else None


def ahead_of_time() -> bool:
    """Whether the kernels come from the extension built at install."""
    return _aot() is not None


@functools.cache
def fresh_jit_cache() -> None:
    """Clear numba's cache of the kernels' files when any kernel source changed since it was
    written (clear_stale on the package). numba keys a cached function on its own file only: a
    loop whose steps (another file, inlined) changed would otherwise run the old steps,
    silently, in a working copy or an editable install after an update. Once per process."""
    from rbhyst.solve.kernels.aot import PACKAGE, SOURCES, source_stamp

    clear_stale(PACKAGE, SOURCES, str(source_stamp()))


def clear_stale(package, sources, stamp: str) -> bool:
    """Delete numba's cache files (``__pycache__/<stem>.*.nbi|nbc``) of every source file under
    ``package`` unless the stamp written beside them the last time equals ``stamp``; then write
    it. Returns whether it cleared. A folder it may not write is left as it is (an installed
    package's kernels are built ahead of time, and stamped, anyway)."""
    from pathlib import Path

    mark = Path(package) / "solve" / "kernels" / "__pycache__" / "kernel-sources.stamp"
    try:
        if mark.read_text() == stamp:
            return False
    except OSError:
        pass
    try:
        for rel in sources:
            for old in ((Path(package) / rel).parent / "__pycache__").glob(Path(rel).stem + ".*.nb[ic]"):
                old.unlink(missing_ok=True)
        mark.parent.mkdir(parents=True, exist_ok=True)
        mark.write_text(stamp)
    except OSError:  # pragma: no cover - a read-only install
        return False
    return True


def kernel(name: str, n: int | None = None):
    """The callable for one of rbhyst.solve.kernels.aot.EXPORTS, for a body of n coordinates
    where the kernel is compiled for each n (built ahead of time for aot.SIZES, else the JIT's)."""
    from rbhyst.solve.kernels.aot import EXPORTS, export_name

    module = _aot()
    if module is not None:
        built = export_name(name, n)
        if built is not None:
            return getattr(module, built)

    fresh_jit_cache()
    mod, func, _ = EXPORTS[name]
    return getattr(importlib.import_module(mod), func)


def jit_compiled(func) -> bool:
    """Whether ``func`` (from :func:`kernel`) is numba's dispatcher, compiled at its first call,
    not the extension's function."""
    return hasattr(func, "py_func")


def cached(dispatchers) -> bool:
    """Whether numba's cache holds compiled code for these dispatchers' current sources.

    A cold cache (a fresh install, an edited kernel) means seconds of compiling before the
    first run: the command line says so once. Any doubt (numba's cache layout is its own)
    counts as cached, so that nothing false is said.
    """
    fresh_jit_cache()
    try:
        return all(bool(d._cache._cache_file._load_index()) for d in dispatchers)
    except Exception:  # pragma: no cover - a numba without this layout
        return True


def run_kernels(adaptive: bool):
    """The dispatchers every run of its kind compiles first (none when they were built ahead of
    time): the fixed-step methods' loop, or the adaptive one's. The kernels a run may or may not
    reach (its error estimate's, the CSV formatter) are not counted: a note that they are not
    compiled yet would be said at every run of a user who never needs them."""
    if ahead_of_time():
        return ()
    if adaptive:
        from rbhyst.solve.kernels.dop853 import _integrate

        return (_integrate,)
    from rbhyst.solve.kernels.loop import run_chunk

    return (run_chunk,)
