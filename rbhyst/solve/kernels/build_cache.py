"""A cache of the extension built ahead of time (rbhyst.solve.kernels.aot), kept between installs.

pip builds a project installed from a folder anew every time (it keeps no wheel of a local
folder), so that ``pip install .`` and then ``pip install ".[test]"`` would compile the kernels
twice, some five minutes each on two cores. setup.py keeps the built extension in a folder of
the user's cache under a key of everything the compiled code depends on: the kernels' sources
(and aot.py, which names their signatures), numba's, llvmlite's and numpy's versions at build
time, the Python and the platform, and the compiler's settings from the environment. The same
key finds the same bytes; anything else compiles again. Standard library only: setup.py runs
it in pip's build environment before rbhyst's dependencies exist.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import sys
import sysconfig
import tempfile
from pathlib import Path

#: the environment variable naming the cache folder, or switching the cache off ("off")
CACHE_VARIABLE = "RBHYST_KERNEL_CACHE"
#: how many builds the cache keeps (the newest): a working copy whose kernels are edited and
#: installed again and again would otherwise fill it, a megabyte a build
KEEP = 8
#: the environment variables that change what the compiler makes
COMPILER_VARIABLES = ("CC", "CFLAGS", "LDFLAGS", "LDSHARED", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES", "NUMBA_OPT")


def cache_folder(environ: dict | None = None) -> Path | None:
    """Where built extensions are kept: ``$RBHYST_KERNEL_CACHE``, else the user's cache folder
    (``$XDG_CACHE_HOME`` or ``~/.cache``; ``%LOCALAPPDATA%`` on Windows) + ``rbhyst/kernels``.
    None when switched off (``RBHYST_KERNEL_CACHE=off``)."""
    env = os.environ if environ is None else environ
    chosen = env.get(CACHE_VARIABLE)
    if chosen:
        return None if chosen.lower() in ("off", "0", "no", "false") else Path(chosen)
    if sys.platform == "win32" and env.get("LOCALAPPDATA"):
        base = Path(env["LOCALAPPDATA"])
    elif env.get("XDG_CACHE_HOME"):
        base = Path(env["XDG_CACHE_HOME"])
    else:
        base = Path(env.get("HOME") or Path.home()) / ".cache"
    return base / "rbhyst" / "kernels"


def _versions() -> dict[str, str]:
    """The versions of the build's compilers, as the build environment has them."""
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for name in ("numba", "llvmlite", "numpy"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "none"
    return out


def build_key(package: Path, sources: tuple[str, ...], environ: dict | None = None,
              versions: dict[str, str] | None = None) -> str:
    """A sha256 of what the compiled extension depends on (see the module's docstring)."""
    env = os.environ if environ is None else environ
    h = hashlib.sha256()

    def add(label: str, data: bytes | str) -> None:
        data = data.encode() if isinstance(data, str) else data
        h.update(f"{label}:{len(data)}:".encode() + data)

    for rel in (*sources, "solve/kernels/aot.py"):
        add(rel, (Path(package) / rel).read_bytes())
    for name, ver in sorted((versions if versions is not None else _versions()).items()):
        add(name, ver)
    add("python", sys.version)
    add("abi", sysconfig.get_config_var("EXT_SUFFIX") or "")
    add("platform", f"{sysconfig.get_platform()} {platform.machine()}")
    for name in COMPILER_VARIABLES:
        add(name, env.get(name, ""))
    return h.hexdigest()


def cached(folder: Path | None, key: str, filename: str) -> Path | None:
    """The extension kept under ``key``, or None (no cache, or not built with this key yet)."""
    if folder is None:
        return None
    path = Path(folder) / key / filename
    if not (path.is_file() and path.stat().st_size > 0):
        return None
    try:
        os.utime(path.parent)  # used now: the newest builds are those prune keeps
    except OSError:
        pass
    return path


def keep(folder: Path | None, key: str, built: Path) -> Path | None:
    """Copy a freshly built extension into the cache under ``key``; the copy is renamed into
    place whole, so that another install reading the cache meanwhile finds all or nothing.
    Returns its path, or None when there is no cache or it cannot be written (never an error:
    the cache only saves time)."""
    if folder is None:
        return None
    target = Path(folder) / key / Path(built).name
    tmp = None
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=".partial-")
        os.close(fd)
        shutil.copyfile(built, tmp)
        os.replace(tmp, target)
    except OSError:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        return None
    prune(Path(folder))
    return target


def prune(folder: Path, keep: int = KEEP) -> list[Path]:
    """Remove all but the ``keep`` newest builds of the cache; only folders named by a key (64 hex
    digits) are ever touched, whatever else a folder chosen by RBHYST_KERNEL_CACHE holds."""
    builds = [p for p in folder.iterdir() if p.is_dir() and len(p.name) == 64
              and all(c in "0123456789abcdef" for c in p.name)]
    builds.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    removed = builds[keep:]
    for old in removed:
        shutil.rmtree(old, ignore_errors=True)
    return removed
