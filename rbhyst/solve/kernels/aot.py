"""The compiled kernels built ahead of time, at install, into the extension ``rbhyst.solve.kernels._aot``.

A command that loads numba spends about a second before its first step (importing numba,
refreshing its target, loading cached code); the same kernels compiled at install into a
plain extension module load in milliseconds. setup.py builds them with numba's ahead-of-time
compiler from the very functions the JIT compiles (no second implementation), without
reference counting (every buffer comes from the caller, as in the JIT kernels) and for a
generic CPU of the platform, so that a built wheel runs on any machine of its kind.
``STAMP`` of the kernels' sources is compiled in: a working copy edited since the build
falls back to the JIT kernels (rbhyst.solve.kernels.compiled), never to stale code.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2]

#: every source file whose code (or constants) the exported kernels compile in
SOURCES = ("model/hysteresis.py", "model/vrm.py", "model/stop.py", "model/signals.py", "solve/kernels/layout.py",
           "solve/kernels/elements.py", "solve/kernels/rotations.py", "solve/kernels/loop.py", "solve/kernels/through.py", "solve/kernels/csvfmt.py", "solve/kernels/reduce.py",
           "solve/kernels/redrive.py", "solve/kernels/modified.py", "solve/kernels/estimate.py",
           "solve/kernels/dop853.py", "solve/kernels/dop853_layout.py", "solve/integrators/steps.py",
           "solve/integrators/chang.py", "solve/integrators/central_difference.py", "solve/integrators/kr_alpha.py",
           "solve/integrators/newmark.py")

#: the numbers of coordinates a kernel whose signature says {n} is built for (one export each,
#: ``name_n3``): the seed's plane body and the body in space; a body of another n (one built by
#: hand) runs the JIT kernels
SIZES = (3, 6)

#: name -> (module, function, signature); {n}: the number of coordinates (M and M^-1 are tuples
#: of n, so that n is a compile-time constant: see rbhyst.solve.integrators.steps)
EXPORTS = {
    "run_chunk": ("rbhyst.solve.kernels.loop", "run_chunk",
                  "i8(i8, f8[:,:,:,::1], UniTuple(f8, {n}), UniTuple(f8, {n}), f8[:,::1], b1, f8[:,::1], f8[::1], i8, f8[::1], "
                  "f8[:,:,::1], f8[::1], f8[:,::1], f8, f8, i8, i8, f8, i8, i8, f8, i8, f8[::1], f8[:,:,::1], f8[:,::1], "
                  "f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], "
                  "f8[::1], i8[::1], b1, f8[::1])"),
    "step_through": ("rbhyst.solve.kernels.through", "step_through",
                     "i8(i8, f8[:,:,:,:,::1], UniTuple(f8, {n}), UniTuple(f8, {n}), f8[:,::1], b1, f8[:,::1], f8[::1], i8, "
                     "f8[::1], f8[:,:,::1], f8[::1], f8[:,::1], i8[:,::1], f8, f8, i8, f8, i8, f8[::1], f8[:,:,::1], "
                     "f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], "
                     "f8[:,::1], f8[::1], b1[::1], i8[::1], f8[:,::1], f8[:,::1], f8[:,::1], i8[::1], b1, f8[::1])"),
    "companion_estimate": ("rbhyst.solve.kernels.estimate", "companion_estimate",
                           "i8(i8, f8[:,:,:,:,::1], UniTuple(f8, {n}), UniTuple(f8, {n}), f8[:,::1], b1, f8[:,::1], "
                           "f8[::1], i8, f8[::1], f8[:,:,::1], f8[::1], i8[:,::1], f8, f8, i8, f8, i8, i8, f8[:,::1], "
                           "f8[::1], i8[::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], f8[::1], f8[:,:,::1], f8[:,::1], "
                           "f8[:,::1], f8[::1], f8[::1], f8[:,::1], i8[::1], i8[::1], f8[::1], i8, i8[::1], f8[:,::1], b1, "
                           "f8[:,::1], b1, f8[:,:,::1], f8[::1], i8[::1], f8[::1], f8, f8, f8, f8[:,::1], f8[:,::1], "
                           "f8[:,::1], f8[::1], b1[::1], f8[:,::1], f8[::1], f8[:,:,::1], f8[:,::1], f8[:,::1], f8[:,::1], "
                           "f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], "
                           "f8[:,::1], b1[::1], f8[:,::1], f8[:,::1], f8[:,::1], i8[::1], f8[:,::1], f8[:,::1], f8[:,::1], "
                           "f8[::1], f8[::1], f8[:,::1], f8[:,::1], i8[::1], b1, f8[::1])"),
    "integrate": ("rbhyst.solve.kernels.dop853", "_integrate",
                  "i8(UniTuple(f8, {n}), f8[:,::1], f8[::1], i8, f8[::1], f8[:,:,::1], f8[:,::1], f8[::1], f8[:,:,::1], f8[:,::1], "
                  "f8[::1], f8, f8[::1], f8[:,::1], f8[::1], f8, i8, f8[:,::1], f8[::1], f8[::1], f8[::1], "
                  "f8[::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], f8[::1], f8[:,::1], "
                  "f8[:,::1], f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], f8[::1])"),
    "decompose": ("rbhyst.solve.kernels.csvfmt", "_decompose",
                  "i8(f8[:,::1], i8[:,::1], i8[:,::1], i1[:,::1], f8[::1])"),
    "render": ("rbhyst.solve.kernels.csvfmt", "_render", "i8(f8[:,::1], i8[:,::1], i8[:,::1], i1[:,::1], u1[::1], i8[::1])"),
    "redrive": ("rbhyst.solve.kernels.redrive", "redrive", "i8(f8[:,:,::1], f8[:,::1], f8[:,::1], f8[:,::1])"),
    "redrive_on": ("rbhyst.solve.kernels.redrive", "redrive_on", "i8(f8[:,:,::1], f8[:,::1], f8[:,::1], f8[:,::1], b1)"),
    "window_source": ("rbhyst.solve.kernels.modified", "window_source",
                      "void(i8, f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], f8[:,::1], f8[:,::1], b1, f8[::1], f8[::1], "
                      "f8[:,::1], f8[::1], f8[::1], f8[::1], f8[:,::1], b1[::1], f8[:,::1], f8[:,::1], f8[::1], f8[::1], "
                      "f8[::1])"),
    "modified": ("rbhyst.solve.kernels.modified", "source_and_offset",
                 "void(i8, f8[:,::1], f8[:,::1], f8[::1], f8[::1], f8[::1], f8[:,::1], b1, f8[:,::1], b1[::1], "
                 "f8[:,::1], f8[:,::1], f8[::1], f8[::1], f8[::1])"),
    "companion_source": ("rbhyst.solve.kernels.modified", "companion_source",
                         "void(i8, f8[:,::1], f8[:,::1], f8[:,::1], f8[::1], f8[:,::1], f8[:,::1], b1, f8[::1], f8[::1], "
                         "f8[:,::1], f8[::1], i8[::1], i8[::1], i8[::1], f8, f8[::1], f8[:,::1], f8[::1], b1[::1], "
                         "f8[:,::1], f8[:,::1], f8[::1], f8[::1], f8[::1])"),
    "reduce_rows": ("rbhyst.solve.kernels.reduce", "reduce_rows",
                    "void(f8[:,:], i8, i8, f8[::1], f8[::1], f8[::1], f8[::1], f8[:,::1], f8[:,::1], "
                    "f8[::1], f8[::1])"),
    "largest_change": ("rbhyst.solve.kernels.reduce", "largest_change",
                       "void(f8[:,:], f8[:,:], f8[:,:], f8[:,::1], f8[:,::1], b1, f8[::1], f8[:,::1], b1, f8[:,:,::1], "
                       "f8[::1], f8[:,::1])"),
    "resultant": ("rbhyst.solve.kernels.reduce", "resultant", "void(f8[:,:], f8[:,::1], f8[:,:])"),
    "neglected_terms": ("rbhyst.solve.kernels.reduce", "neglected_terms",
                        "f8(f8[::1], f8[::1], f8[::1], f8[:,::1], f8[::1], f8[::1], f8[::1], f8[::1])"),
    "static_update": ("rbhyst.solve.kernels.elements", "static_update",
                      "void(f8[:,::1], f8[::1], i8, f8[::1], f8[:,:,::1], f8[::1], f8[:,:,::1], i8, f8[:,::1], "
                      "f8[::1], f8[:,::1], f8[::1])"),
}


def export_name(name: str, n: int | None = None) -> str | None:
    """The extension's name for kernel ``name`` built for n coordinates (None: not built for it)."""
    if "{n}" not in EXPORTS[name][2]:
        return name
    return f"{name}_n{n}" if n in SIZES else None


def source_stamp() -> int:
    """A 60-bit digest of the kernels' sources (as an int: what an exported function can return)."""
    h = hashlib.sha256()
    for rel in SOURCES:
        h.update(rel.encode())
        h.update((PACKAGE / rel).read_bytes())
    return int(h.hexdigest()[:15], 16)


def compiler():
    """numba's ahead-of-time compiler set up with every export (imports numba: build time only)."""
    import importlib

    from numba.pycc import CC

    _release_the_gil()
    cc = CC("_aot", source_module="rbhyst.solve.kernels.aot")
    cc.use_nrt = False  # as the JIT kernels: no reference counting, every buffer from the caller
    cc.verbose = False
    for name, (module, func, sig) in EXPORTS.items():
        fn = getattr(importlib.import_module(module), func)
        for n in SIZES if "{n}" in sig else (None,):
            cc.export(export_name(name, n), sig.format(n=n))(fn.py_func)
    stamp = source_stamp()
    cc.export("stamp", "i8()")(eval(f"lambda: {stamp}"))  # the sources it was built from
    return cc


def _release_the_gil() -> None:
    """Every export lets go of Python's lock while it runs, as ``nogil=True`` makes a JIT kernel:
    threads format time_history.csv while the run steps (rbhyst.results.writers), and the
    companion's check steps beside the companion (rbhyst.solve.estimate). numba's
    ahead-of-time compiler has no option for it; it takes the flags of its compilation from
    this name, so that a subclass setting release_gil there is the whole change."""
    import numba.pycc.compiler as pycc
    from numba.core.compiler import Flags

    class ReleasingGil(Flags):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.release_gil = True

    if pycc.Flags.__name__ != "ReleasingGil":
        pycc.Flags = ReleasingGil
