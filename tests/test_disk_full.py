"""A disk that fills: one `error:` line naming the folder and the space it needed, exit 2, the
earlier results intact, nothing staged left behind, and a sweep's store never complete, its
kept cases each proving their content.

Two ways: a real small filesystem (tmpfs, where this machine lets the test mount one), and
ENOSPC injected at chosen writes of a run in this process (everywhere)."""

from __future__ import annotations

import builtins
import errno
import io
import json
import shutil
import subprocess
import uuid
from pathlib import Path

import pytest
import tomli_w

from rbhyst.files.outdir import STAGING_PREFIX
from rbhyst.analyses.sweep.store import FOLDER, JOURNAL, line_sum
from conftest import DECKS, invoke, seed_deck, snapshot, write_deck


@pytest.fixture
def small_disk(tmp_path):
    """A 3 MB tmpfs; remount(size) grows it. Skips where mounting is not allowed."""
    where = tmp_path / f"disk-{uuid.uuid4().hex[:8]}"
    where.mkdir()
    if shutil.which("mount") is None:
        pytest.skip("no mount command")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(where)], capture_output=True)
    if r.returncode != 0:
        pytest.skip("cannot mount a small filesystem here (needs root)")

    def remount(size: str) -> None:
        subprocess.run(["mount", "-o", f"remount,size={size}", str(where)], check=True)

    try:
        yield where, remount
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


def errors(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if ln.startswith("error:")]


def no_traceback(err: str) -> bool:
    return "Traceback" not in err and "OSError" not in err


def deck_of(folder: Path, duration: float, name: str) -> Path:
    data = seed_deck(duration=duration)
    return write_deck(folder, data, name)


# ---------------------------------------------------------------- a real small filesystem


def test_a_csv_that_cannot_fit_is_refused_naming_the_folder(small_disk, tmp_path):
    disk, _ = small_disk
    deck = deck_of(tmp_path, 40.0, "long")
    code, err = invoke("run", deck, "--out", disk / "out")
    assert code == 2 and no_traceback(err), err
    (line,) = errors(err)
    assert line.startswith(f"error: {disk / 'out'}: analysis.duration, analysis.dt, output.every: the run would "
                           "write 4e+04 rows")
    assert "MB free on the folder's disk: output.every = " in line
    assert not (disk / "out").exists()


def test_plots_that_do_not_fit_leave_the_earlier_results(small_disk, tmp_path):
    disk, _ = small_disk
    out = disk / "out"
    code, err = invoke("run", deck_of(tmp_path, 1.0, "short"), "--out", out)
    assert code == 0, err
    before = snapshot(out)
    # its CSV fits beside the earlier results; the plots do not (2.8 s: the CSV's estimate, 1.70 MB,
    # within 0.9 of the 2.0 MB left, and its figures, 0.68 MB, beyond what its 1.46 MB leaves)
    code, err = invoke("run", deck_of(tmp_path, 2.8, "longer"), "--out", out)
    assert code == 2 and no_traceback(err), err
    (line,) = errors(err)
    assert line.startswith(f"error: {out}: no space left on its disk for the outputs: they need more than the ")
    assert line.endswith("MB that was free; nothing in the folder was changed: free some space or choose another "
                         "output folder")
    assert snapshot(out) == before
    assert not [p for p in out.iterdir() if p.name.startswith(STAGING_PREFIX)]


def test_a_sweep_stops_cleanly_and_completes_once_there_is_space(small_disk):
    pytest.importorskip("pyarrow")
    disk, remount = small_disk
    shutil.copytree(DECKS / "records", disk / "records")
    shutil.copy(DECKS / "seed_wri.toml", disk / "seed_wri.toml")
    sweep = disk / "sweep.toml"
    sweep.write_text(tomli_w.dumps({"deck": "seed_wri.toml", "scale": {"factors": [0.5, 0.75, 1.0, 1.25, 1.5, 2.0]},
                                    "vary": {"analysis.duration": [4.0]}}))
    out = disk / "results" / "sweep"
    code, err = invoke("sweep", sweep, "--no-plots", "--save-histories", "--workers", "1")
    assert code == 2 and no_traceback(err), err
    (line,) = errors(err)
    assert line.startswith(f"error: {out / FOLDER}: no space left on its disk for the finished cases: they need "
                           "more than the ")
    kept = [json.loads(ln) for ln in (out / FOLDER / JOURNAL).read_bytes().splitlines()[1:]]
    assert all(e["sha256"] == line_sum(e) for e in kept)  # whole lines only
    assert f"; {len(kept)} finished case" in line and "the same command computes the rest" in line
    assert not (out / "cases.csv").exists()  # never complete
    assert not list((out / FOLDER / "histories").glob(".*.partial"))
    remount("40m")
    code, err = invoke("sweep", sweep, "--no-plots", "--save-histories")
    assert code == 0, err
    assert f"{len(kept)} already in the folder" in err
    rows = (out / "cases.csv").read_text().splitlines()
    assert len(rows) == 7 and all(",ok," in r for r in rows[1:])


# ---------------------------------------------------------------- ENOSPC at a chosen write


class _Full:
    """Files opened for writing whose ``fail_at``-th write (counted over all of them) raises
    ENOSPC, as a filesystem that fills there would."""

    def __init__(self, fail_at: int | None):
        self.fail_at, self.count = fail_at, 0

    def wrap(self, real_open):
        def opener(file, mode="r", *args, **kwargs):
            fh = real_open(file, mode, *args, **kwargs)
            if not any(c in mode for c in "wax+"):
                return fh
            real_write, full = fh.write, self  # (io classes take no attributes: a proxy instead)

            def write(data):
                full.count += 1
                if full.fail_at is not None and full.count >= full.fail_at:
                    raise OSError(errno.ENOSPC, "No space left on device")
                return real_write(data)

            return _Proxy(fh, write)
        return opener


class _Proxy:
    def __init__(self, fh, write):
        self._fh, self.write = fh, write

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()

    def __iter__(self):
        return iter(self._fh)


def injected(monkeypatch, fail_at):
    full = _Full(fail_at)
    real = builtins.open
    monkeypatch.setattr(builtins, "open", full.wrap(real))
    monkeypatch.setattr(io, "open", full.wrap(real))
    return full


def test_enospc_at_any_write_of_a_run(tmp_path, monkeypatch):
    deck = deck_of(tmp_path, 0.5, "deck")
    out = tmp_path / "out"
    code, err = invoke("run", deck, "--out", out)
    assert code == 0, err
    before = snapshot(out)
    with monkeypatch.context() as m:
        counted = injected(m, None)
        code, err = invoke("run", deck, "--out", out)
        assert code == 0, err
    writes = counted.count
    assert writes > 20  # the CSV, summary.json, the manifest and every PNG's chunks
    before = snapshot(out)
    for k in sorted({1, 2, 3, writes // 4, writes // 2, 3 * writes // 4, writes - 1}):
        with monkeypatch.context() as m:
            injected(m, k)
            code, err = invoke("run", deck, "--out", out)
        assert code == 2 and no_traceback(err), (k, err)
        (line,) = errors(err)
        assert line.startswith(f"error: {out}: no space left on its disk for the outputs: "), (k, line)
        assert snapshot(out) == before, k  # the earlier results, and nothing staged
    # the last write is the manifest once every file is in: the results stand, under the
    # manifest written before the files moved, which names them all
    with monkeypatch.context() as m:
        injected(m, writes)
        code, err = invoke("run", deck, "--out", out)
    assert code == 0, err
    after = snapshot(out)
    assert set(after) == set(before) and after["time_history.csv"][0] == before["time_history.csv"][0]


def test_a_record_that_cannot_be_written_leaves_the_old_one(tmp_path, monkeypatch):
    rec = tmp_path / "rec.csv"
    opts = ("--duration", "0.5", "--seed", "3")
    assert invoke("make-record", rec, *opts)[0] == 0
    before = snapshot(tmp_path)
    with monkeypatch.context() as m:
        injected(m, 1)
        code, err = invoke("make-record", rec, "--duration", "0.7", "--seed", "3")
    assert code == 2 and no_traceback(err), err
    (line,) = errors(err)
    assert line.startswith(f"error: {tmp_path}: no space left on its disk for rec.csv (")
    assert line.endswith(" kB); rec.csv was not changed: free some space or choose another output folder")
    assert snapshot(tmp_path) == before
