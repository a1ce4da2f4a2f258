"""A finished sweep is finished: run again, it computes nothing and leaves its tables and figures
as they stand, unless one is missing, older than the store, made from other cases, or --redraw.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from rbhyst.analyses.sweep.store import FOLDER, JOURNAL
from rbhyst.sweep import load_sweep, run_sweep
from test_sweep import SWAPPED, SYN, project, write_sweep  # noqa: F401 (project: the fixture)
from conftest import invoke

OUT = ("results", "sweep")


def two_motions(duration: float = 0.5) -> dict:
    return {"deck": "seed_wri.toml", "motions": [{"name": "syn", **SYN}, {"name": "swapped", **SWAPPED}],
            "scale": {"factors": [0.5, 1.5]}, "vary": {"analysis.duration": [duration]}}


def stamps(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file's (inode, mtime in ns): a file written again (replaced) changes both."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in folder.iterdir() if p.is_file()}


def test_a_finished_sweep_run_again_writes_nothing_and_draws_nothing(project):
    sweep = write_sweep(project, two_motions())
    out = project.joinpath(*OUT)
    first = run_sweep(load_sweep(sweep), workers=1)
    assert first.written and first.computed == 4
    about = json.loads((out / "sweep.json").read_text())
    assert about["files"] == ["cases.csv", "ida.png", "stats.csv", "sweep.json"]
    before = stamps(out)
    # in a process of its own: the command neither draws nor imports matplotlib, numba or dask
    probe = ("import sys; from rbhyst.cli import main\n"
             "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
             "print(sorted(m for m in ('matplotlib', 'numba', 'dask', 'distributed') if m in sys.modules))")
    # (the rbhyst this test imports, as installed: a source tree beside an installed package has
    # no compiled kernels of its own, and would import numba to compile them)
    done = subprocess.run([sys.executable, "-c", probe, "sweep", sweep.name], cwd=project, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
    assert "nothing to compute" in done.stderr
    assert "its tables and figures stand for these cases, newer than their store (--redraw writes them again)" \
        in done.stderr and "wrote" not in done.stderr
    assert stamps(out) == before


def test_what_is_missing_older_than_the_store_or_asked_for_is_written_again(project):
    sweep = write_sweep(project, two_motions())
    out = project.joinpath(*OUT)
    run_sweep(load_sweep(sweep), workers=1)
    cases = (out / "cases.csv").read_bytes()
    # a figure removed: written again, with everything else, from the same cases
    (out / "ida.png").unlink()
    again = run_sweep(load_sweep(sweep), workers=1)
    assert again.written and again.computed == 0 and (out / "ida.png").is_file()
    assert (out / "cases.csv").read_bytes() == cases
    # a store newer than the files (a journal rewritten after they were): written again
    before = stamps(out)
    journal = out / FOLDER / JOURNAL
    later = max(t for _, t in before.values()) + 1
    os.utime(journal, ns=(later, later))
    assert run_sweep(load_sweep(sweep), workers=1).written
    assert all(stamps(out)[name] != before[name] for name in ("cases.csv", "ida.png", "stats.csv", "sweep.json"))
    # standing: not written; --redraw: written
    before = stamps(out)
    assert not run_sweep(load_sweep(sweep), workers=1).written and stamps(out) == before
    code, err = invoke("sweep", sweep, "--redraw")
    assert code == 0 and "nothing to compute" in err and f"wrote {out}" in err, err
    assert stamps(out)["ida.png"] != before["ida.png"]


def test_a_sweep_of_fewer_finished_cases_writes_its_own_tables(project):
    out = project.joinpath(*OUT)
    run_sweep(load_sweep(write_sweep(project, two_motions())), workers=1, plots=False)
    assert len((out / "cases.csv").read_text().splitlines()) == 5
    # one motion left out: every case is in the store, but the tables were of four cases
    fewer = two_motions()
    fewer["motions"] = fewer["motions"][:1]
    outcome = run_sweep(load_sweep(write_sweep(project, fewer)), workers=1, plots=False)
    assert outcome.computed == 0 and outcome.written
    rows = (out / "cases.csv").read_text().splitlines()
    assert len(rows) == 3 and all(",syn," in r for r in rows[1:])
    # the figures asked for where there were none: drawn
    assert not (out / "ida.png").exists()
    assert run_sweep(load_sweep(write_sweep(project, fewer)), workers=1).written
    assert (out / "ida.png").is_file()


def test_the_outputs_sum_is_the_sha256_of_the_whole_json():
    """outputs_sum's digest, its rows encoded one at a time, is the sha256 of the one JSON text
    of everything (so a finished sweep of an earlier version stands): empty and long lists,
    text to quote and escape, nested dicts to sort, inf and a set (repr) among them."""
    import hashlib
    import random

    from rbhyst.analyses.sweep.uptodate import json_sum

    rng = random.Random(0)
    for trial in range(100):
        rows = [[rng.random(), str(rng.random()), 'a,"b"\n', None, {"z": 1, "a": [1, 2.5]}, float("inf"), "é"]
                for _ in range(rng.randint(0, 4))]
        body = ["0.2.0", ["h", "é"], rows, [None, "ab"] * rng.randint(0, 2), ["k"], "factors", [0.5],
                {"b": None, "a": "kg"}, None, False, {1, 2} if trial % 5 == 0 else True]
        text = json.dumps(body, sort_keys=True, separators=(",", ":"), default=repr)
        assert json_sum(body, long=(2, 3)) == hashlib.sha256(text.encode()).hexdigest()
