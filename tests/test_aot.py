"""The kernels compiled ahead of time at install run the same code as numba's JIT, to the bit."""

from __future__ import annotations

import atexit
import functools
import json
import os
import subprocess
import sys
import tempfile

import pytest

from conftest import DECKS

CODE = r"""
import json, sys
import os, rbhyst
from rbhyst.solve.kernels.compiled import ahead_of_time
if not os.environ.get("RBHYST_JIT") and not ahead_of_time():
    print(json.dumps(None)); sys.exit()
for deck, method in zip(sys.argv[1::2], sys.argv[2::2]):
    res = rbhyst.run(deck, integrator=method)
    print(json.dumps({"numba": "numba" in sys.modules, "peaks": res.extremes.peaks(),
                      "last": res.table[-1].tolist(), "accuracy": res.accuracy["estimated_error"]}))
"""

SCENES = [("machine_on_mounts.toml", "chang"), ("machine_on_mounts.toml", "newmark"),
          ("machine_on_mounts.toml", "adaptive"), ("seed_wri.toml", "chang")]


def _command(scenes) -> list[str]:
    return [sys.executable, "-c", CODE, *(str(DECKS / d) if i % 2 == 0 else d
                                          for pair in scenes for i, d in enumerate(pair))]


def installed(env_extra: dict, scenes, cwd) -> list | None:
    """Run in a folder outside the source tree, so that the installed package is imported."""
    env = {**os.environ, **env_extra}
    out = subprocess.run(_command(scenes), cwd=cwd, env=env, capture_output=True, text=True, check=True)
    lines = [json.loads(line) for line in out.stdout.splitlines() if line.strip()]
    return None if lines == [None] else lines


@functools.cache
def _jit_job() -> subprocess.Popen:
    """The JIT's runs of every scene, in one process started before the first test (conftest:
    start_in_background): numba compiling the kernels takes minutes on one core, which the rest
    of the suite uses meanwhile on the other."""
    cwd = tempfile.mkdtemp(prefix="rbhyst-jit-")
    return subprocess.Popen(_command(SCENES), cwd=cwd, env={**os.environ, "RBHYST_JIT": "1"},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def start_in_background() -> None:
    from rbhyst.solve.kernels.compiled import ahead_of_time

    if ahead_of_time():  # (otherwise the test skips, and nothing is compared)
        atexit.register(lambda job: job.poll() is None and job.kill(), _jit_job())


@functools.cache
def _jit_results() -> dict:
    job = _jit_job()
    out, err = job.communicate()
    assert job.returncode == 0, err
    return dict(zip(SCENES, (json.loads(line) for line in out.splitlines() if line.strip())))


@pytest.mark.parametrize("deck, method", SCENES)
def test_ahead_of_time_equals_jit_and_loads_no_numba(tmp_path, deck, method):
    """The machine with exact rotations (its estimate the adaptive solutions'), and the seed deck,
    whose estimate is its companion's (the run's modified equation, the re-driven forces)."""
    aot = installed({}, [(deck, method)], tmp_path)
    if aot is None:
        pytest.skip("the installed rbhyst has no kernels built ahead of time (an editable install, or no compiler)")
    jit = _jit_results()[(deck, method)]
    aot = aot[0]
    assert aot["numba"] is False  # a run loads no numba at all
    assert jit["numba"] is True  # the comparison is with the JIT's kernels
    assert aot["peaks"] == jit["peaks"] and aot["last"] == jit["last"] and aot["accuracy"] == jit["accuracy"]


def test_a_stale_build_is_never_used(tmp_path, monkeypatch):
    """The build is stamped with its sources: once they change, the JIT kernels are used."""
    from rbhyst.solve.kernels import aot, compiled

    compiled._aot.cache_clear()
    monkeypatch.setattr(aot, "source_stamp", lambda: -1)
    try:
        assert compiled.ahead_of_time() is False
        assert compiled.kernel("run_chunk").__module__ == "rbhyst.solve.kernels.loop"
    finally:
        compiled._aot.cache_clear()


def test_a_changed_kernel_source_clears_the_cached_kernels(tmp_path):
    """numba keys a cached kernel on its own file: an edited step (inlined into the loop from
    another file) would run stale. The cache of every kernel source goes when any changed."""
    from rbhyst.solve.kernels.compiled import clear_stale

    sources = ("solve/kernels/loop.py", "solve/integrators/steps.py")
    for rel in sources:
        cache = tmp_path / rel.rsplit("/", 1)[0] / "__pycache__"
        cache.mkdir(parents=True, exist_ok=True)
        stem = rel.rsplit("/", 1)[1][:-3]
        (cache / f"{stem}.f-12.py311.nbi").write_text("index")
        (cache / f"{stem}.f-12.py311.1.nbc").write_text("code")
        (cache / f"{stem}.cpython-311.pyc").write_text("bytecode")
    assert clear_stale(tmp_path, sources, "1")
    left = sorted(p.name for p in tmp_path.rglob("__pycache__/*"))
    assert left == ["kernel-sources.stamp", "loop.cpython-311.pyc", "steps.cpython-311.pyc"]
    # the same sources again: nothing cleared; a new one cached since stays
    (tmp_path / "solve/kernels/__pycache__/loop.f-12.py311.nbi").write_text("index")
    assert not clear_stale(tmp_path, sources, "1")
    assert (tmp_path / "solve/kernels/__pycache__/loop.f-12.py311.nbi").exists()
    assert clear_stale(tmp_path, sources, "2")
    assert not (tmp_path / "solve/kernels/__pycache__/loop.f-12.py311.nbi").exists()


def test_a_plan_calls_its_loop_ahead_only_where_the_jit_compiles_it(monkeypatch):
    """A numba dispatcher is compiled (or loaded from its cache) when the plan is made, not in
    the first chunk's time; the extension's loop needs no such call."""
    from rbhyst.model.deck import load_deck
    from rbhyst.results import analysis
    from rbhyst.solve import plan as planning
    from rbhyst.solve.kernels.compiled import jit_compiled
    from rbhyst.solve.kernels.loop import run_chunk

    assert jit_compiled(run_chunk)
    assert not jit_compiled(len)
    calls = []
    real = planning.FixedStepPlan._call
    monkeypatch.setattr(planning.FixedStepPlan, "_call", lambda self, *a, **k: calls.append(a[5]) or real(self, *a, **k))
    system, settings = analysis.scene(load_deck(DECKS / "seed_wri.toml"))
    made = analysis.plan(system, settings)
    assert calls == ([0] if jit_compiled(made._loop) else [])


def test_a_run_under_gravity_loads_no_numba_either(tmp_path):
    """The static equilibrium's steps (rbhyst.solve.static) are a kernel built at install too."""
    from conftest import write_deck
    from test_equipment import hanging_deck

    path = write_deck(tmp_path, hanging_deck())
    code = ("import json, sys, rbhyst\nfrom rbhyst.solve.kernels.compiled import ahead_of_time\n"
            "res = rbhyst.run(sys.argv[1])\n"
            "print(json.dumps([ahead_of_time(), 'numba' in sys.modules, res.summary()['static'] is not None]))")
    out = subprocess.run([sys.executable, "-c", code, str(path)], cwd=tmp_path, capture_output=True, text=True,
                         check=True)
    built, numba, static = json.loads(out.stdout.splitlines()[-1])
    if not built:
        pytest.skip("the installed rbhyst has no kernels built ahead of time (an editable install, or no compiler)")
    assert static and numba is False
