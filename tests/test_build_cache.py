"""The kernels built at install are kept in the user's cache under a key of what they depend on,
so that a second install of the same sources copies them instead of compiling (setup.py)."""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig

from conftest import ROOT

from rbhyst.solve.kernels import build_cache
from rbhyst.solve.kernels.aot import PACKAGE, SOURCES

VERSIONS = {"numba": "0.60.0", "llvmlite": "0.43.0", "numpy": "2.0.0"}


def copy_of_sources(tmp_path):
    """The kernels' sources (and aot.py) copied to a folder of their own, to be edited."""
    for rel in (*SOURCES, "solve/kernels/aot.py"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes((PACKAGE / rel).read_bytes())
    return tmp_path


def test_the_key_follows_sources_versions_and_compiler_settings(tmp_path):
    pkg = copy_of_sources(tmp_path)
    key = build_cache.build_key(pkg, SOURCES, environ={}, versions=VERSIONS)
    assert key == build_cache.build_key(pkg, SOURCES, environ={"UNRELATED": "1"}, versions=dict(VERSIONS))
    assert key != build_cache.build_key(pkg, SOURCES, environ={}, versions={**VERSIONS, "numba": "0.61.0"})
    assert key != build_cache.build_key(pkg, SOURCES, environ={}, versions={**VERSIONS, "numpy": "1.26.4"})
    assert key != build_cache.build_key(pkg, SOURCES, environ={"CFLAGS": "-O0"}, versions=VERSIONS)
    step = pkg / "solve/integrators/steps.py"
    step.write_text(step.read_text() + "\n# an edit\n")
    assert key != build_cache.build_key(pkg, SOURCES, environ={}, versions=VERSIONS)
    aot = pkg / "solve/kernels/aot.py"
    before = build_cache.build_key(pkg, SOURCES, environ={}, versions=VERSIONS)
    aot.write_text(aot.read_text().replace('"i8(i8, f8[:,:,:,::1]', '"i8(i4, f8[:,:,:,::1]', 1))
    assert before != build_cache.build_key(pkg, SOURCES, environ={}, versions=VERSIONS)


def test_the_cache_folder_is_the_users_unless_named_or_switched_off(tmp_path):
    assert build_cache.cache_folder({"HOME": "/home/u"}) == build_cache.Path("/home/u/.cache/rbhyst/kernels")
    xdg = {"HOME": "/home/u", "XDG_CACHE_HOME": "/c"}
    assert build_cache.cache_folder(xdg) == build_cache.Path("/c/rbhyst/kernels")
    assert build_cache.cache_folder({"RBHYST_KERNEL_CACHE": str(tmp_path)}) == tmp_path
    assert build_cache.cache_folder({"RBHYST_KERNEL_CACHE": "off", "HOME": "/home/u"}) is None


def test_kept_and_found_again_whole(tmp_path):
    built = tmp_path / "_aot.so"
    built.write_bytes(b"\x7fELF compiled")
    assert build_cache.cached(tmp_path / "cache", "k", "_aot.so") is None
    kept = build_cache.keep(tmp_path / "cache", "k", built)
    assert kept == build_cache.cached(tmp_path / "cache", "k", "_aot.so")
    assert kept.read_bytes() == built.read_bytes()
    assert [p.name for p in kept.parent.iterdir()] == ["_aot.so"]  # no partial copy left
    assert build_cache.cached(tmp_path / "cache", "other", "_aot.so") is None
    assert build_cache.keep(None, "k", built) is None and build_cache.cached(None, "k", "_aot.so") is None
    (tmp_path / "ro").write_text("a file where the cache folder would be")
    assert build_cache.keep(tmp_path / "ro", "k", built) is None  # cannot write: no error, no cache


def test_the_cache_keeps_the_newest_builds_and_nothing_else_is_touched(tmp_path):
    built = tmp_path / "_aot.so"
    built.write_bytes(b"compiled")
    cache = tmp_path / "cache"
    keys = [f"{k:064x}" for k in range(build_cache.KEEP + 3)]
    for age, key in enumerate(keys):
        build_cache.keep(cache, key, built)
        os.utime(cache / key, (1e9 + age, 1e9 + age))  # each newer than the one before
    (cache / "notes").mkdir()
    build_cache.keep(cache, keys[-1], built)
    left = sorted(p.name for p in cache.iterdir())
    assert left == sorted(keys[-build_cache.KEEP:] + ["notes"])


def test_setup_copies_a_cached_build_instead_of_compiling(tmp_path):
    """setup.py's build_ext with the extension in the cache under the key of these sources and
    this environment's numba: the built module is the cached file's bytes, made in seconds (a
    compile takes minutes: the timeout would fail it)."""
    cache = tmp_path / "cache"
    key = build_cache.build_key(PACKAGE, SOURCES)
    name = "_aot" + sysconfig.get_config_var("EXT_SUFFIX")
    (cache / key).mkdir(parents=True)
    (cache / key / name).write_bytes(b"the cached extension")
    env = {**os.environ, "RBHYST_KERNEL_CACHE": str(cache)}
    env.pop("RBHYST_NO_AOT", None)
    out = subprocess.run([sys.executable, "-c", BUILD, str(tmp_path / "lib"), str(tmp_path / "temp")], check=False,
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=180)
    assert out.returncode == 0, out.stderr
    assert "from the cache" in out.stderr and "compiling the kernels" not in out.stderr
    assert (tmp_path / "lib/rbhyst/solve/kernels" / name).read_bytes() == b"the cached extension"


#: setup.py's build_ext run on its own (setup() itself wants the setuptools of pyproject's
#: build-system, which an environment for tests need not have)
BUILD = """
import runpy, sys, setuptools
setuptools.setup = lambda **kw: None
ns = runpy.run_path("setup.py")
dist = setuptools.Distribution({"name": "rbhyst", "ext_modules": ns["extensions"]()})
cmd = ns["BuildKernels"](dist)
cmd.build_lib, cmd.build_temp = sys.argv[1], sys.argv[2]
cmd.ensure_finalized()
cmd.run()
"""
