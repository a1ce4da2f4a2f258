"""Builds rbhyst's compiled kernels ahead of time (rbhyst/solve/kernels/aot.py) as the extension
rbhyst.solve.kernels._aot; everything else is in pyproject.toml.

Where the build cannot compile them (no C compiler, an unusual platform) the install still
succeeds: rbhyst then compiles them with numba on first use and caches them.
"""

import os
import sys

from setuptools import setup
from setuptools.command.build_ext import build_ext


def warn(msg: str) -> None:
    print(f"warning: rbhyst's kernels are not compiled ahead of time ({msg}); "
          "numba compiles them on first use instead", file=sys.stderr)


class BuildKernels(build_ext):
    def build_extension(self, ext):
        try:
            os.makedirs(self.build_temp, exist_ok=True)
            objects, _ = ext._cc._compile_object_files(self.build_temp)  # numba's ahead-of-time compiler
            ext.extra_objects = objects
            super().build_extension(ext)
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
