"""Builds rbhyst's compiled kernels ahead of time (rbhyst/solve/kernels/aot.py) as the extension
rbhyst.solve.kernels._aot; everything else is in pyproject.toml.

Compiling them takes some five minutes on two cores. The built extension is kept in the user's
cache (rbhyst/solve/kernels/build_cache.py) under a key of its sources, numba's version and the
platform, so that a second install of the same sources (``pip install .`` then
``pip install ".[test]"``) copies it instead of compiling again. pip shows what this says with
``pip install -v``.

Where the build cannot compile them (no C compiler, an unusual platform) the install still
succeeds: rbhyst then compiles them with numba on first use and caches them.
"""

import os
import shutil
import sys
import time

from setuptools import setup
from setuptools.command.build_ext import build_ext


def say(msg: str) -> None:
    print(f"rbhyst: {msg}", file=sys.stderr, flush=True)


def warn(msg: str) -> None:
    say(f"warning: the kernels are not compiled ahead of time ({msg}); numba compiles them on first use instead")


class BuildKernels(build_ext):
    def build_extension(self, ext):
        try:
            from rbhyst.solve.kernels import build_cache
            from rbhyst.solve.kernels.aot import PACKAGE, SOURCES

            target = self.get_ext_fullpath(ext.name)
            folder = build_cache.cache_folder()
            key = build_cache.build_key(PACKAGE, SOURCES)
            found = build_cache.cached(folder, key, os.path.basename(target))
            if found is not None:
                os.makedirs(os.path.dirname(target) or ".", exist_ok=True)
                shutil.copyfile(found, target)
                say(f"the kernels built ahead of time come from the cache {found.parent} (same sources, "
                    "numba and platform): no compiling")
                return
            kept_in = (f"kept in {folder} for the next install" if folder is not None
                       else "RBHYST_KERNEL_CACHE=off: not kept")
            say(f"compiling the kernels ahead of time with numba (some 5 minutes on 2 cores; {kept_in})")
            start = time.perf_counter()
            os.makedirs(self.build_temp, exist_ok=True)
            objects, _ = ext._cc._compile_object_files(self.build_temp)  # numba's ahead-of-time compiler
            ext.extra_objects = objects
            super().build_extension(ext)
            kept = build_cache.keep(folder, key, target)
            say(f"kernels compiled in {time.perf_counter() - start:.0f} s"
                + (f", kept in {kept.parent}" if kept is not None else ""))
        except Exception as err:  # an optional speed-up: never a failed install
            warn(f"{err.__class__.__name__}: {err}")


def extensions():
    if os.environ.get("RBHYST_NO_AOT"):
        return []
    try:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from rbhyst.solve.kernels.aot import compiler

        ext = compiler().distutils_extension(optional=True)
        ext.depends = []  # (numba names its source by absolute path, which a manifest cannot hold)
        return [ext]
    except Exception as err:
        warn(f"{err.__class__.__name__}: {err}")
        return []


setup(ext_modules=extensions(), cmdclass={"build_ext": BuildKernels})
