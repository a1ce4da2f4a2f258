"""Output folders that hold other files: rbhyst replaces and removes only what it wrote itself.

Every writing command goes into a folder holding the deck and the user's notes; nothing of
theirs may change (bytes and mtimes), a file in the way is refused with one line (exit 2),
and an interrupted command (KeyboardInterrupt mid-write, a real SIGTERM or Ctrl-C) leaves
the earlier results and no hidden folder.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import rbhyst.files.outdir
from rbhyst.analyses.calibration import protocol
from rbhyst.cli import RECORD_MARK
from rbhyst.model.deck import Loops, parse_deck
from rbhyst.errors import InputError
from rbhyst.model.vrm import loop
from rbhyst.files.outdir import MANIFEST, STAGING_PREFIX, read_manifest, staged_directory
from rbhyst.model.records import read_table
from conftest import TABLE3_SHEAR, invoke, seed_deck, snapshot, square_linear_deck, write_deck


def entries(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*")}


def manifest_files(folder: Path) -> set[str]:
    return set(json.loads((folder / MANIFEST).read_text())["files"])


def no_staging_left(root: Path) -> bool:
    return not [p for p in root.rglob("*") if p.name.startswith(STAGING_PREFIX) or p.name.endswith(".partial")]


def user_folder(root: Path) -> Path:
    """The deck, measured loops for calibrate, and the user's notes, all in one folder."""
    folder = root / "work"
    folder.mkdir()
    deck = seed_deck(duration=0.2)
    deck["loops"] = {"amplitude": 0.01, "cycles": 1, "points_per_cycle": 200}
    write_deck(folder, deck)
    p = parse_deck({"hysteresis": {"wri_shear": TABLE3_SHEAR}}).hysteresis["wri_shear"].array()
    _, u = protocol(Loops(amplitude=[0.005, 0.01], cycles=2, points_per_cycle=100))
    f = loop(p, u)[0]
    rows = "\n".join(f"{a * 1e3:.10g},{b * 1e-3:.10g}" for a, b in zip(u, f))
    (folder / "data.csv").write_text(f"u_mm,f_kN\n{rows}\n")
    (folder / "notes.txt").write_text("my notes: do not lose\n")
    (folder / "ground.csv").write_text("time_s,acc_g\n" + "".join(f"{0.01 * k:.2f},{0.1 * np.sin(k):.6f}\n"
                                                                   for k in range(200)))
    return folder


# command -> (arguments given the folder and the output folder, the files it writes, one of them)
COMMANDS = {
    "run": (lambda d, out: ["run", d / "deck.toml", "--no-plots", "--out", out],
            {"time_history.csv", "summary.json"}, "summary.json"),
    "study": (lambda d, out: ["study", d / "deck.toml", "--integrators", "chang", "--dt", "0.002,0.001",
                              "--no-plots", "--out", out],
              {"study.csv", "study.json"}, "study.csv"),
    "calibrate-plot": (lambda d, out: ["calibrate-plot", d / "deck.toml", "--set", "wri_shear", "--out", out],
                       {"loops.png", "loops_wri_shear.csv", "summary.json"}, "summary.json"),
    "calibrate": (lambda d, out: ["calibrate", d / "data.csv", "--set", "wri_shear", "--init", d / "deck.toml",
                                  "--free", "alpha", "--starts", "1", "--out", out],
                  {"fitted.toml", "fit.json", "loops.png", "loops_wri_shear.csv"}, "fit.json"),
    "spectrum": (lambda d, out: ["spectrum", d / "ground.csv", "--units", "g", "--periods", "0.1,1", "--out", out],
                 {"spectra.csv", "spectra.png"}, "spectra.csv"),
    "transmissibility": (lambda d, out: ["transmissibility", d / "deck.toml", "--direction", "x1", "--amplitude",
                                         "0.1", "--units", "g", "--frequencies", "5,10", "--workers", "1",
                                         "--out", out],
                         {"transmissibility.csv", "transmissibility.json", "transmissibility.png"},
                         "transmissibility.csv"),
}


@pytest.mark.parametrize("command", COMMANDS)
def test_into_the_decks_folder_refuses_a_file_in_the_way_and_keeps_the_rest(tmp_path, command):
    args, outputs, clash = COMMANDS[command]
    folder = user_folder(tmp_path)
    (folder / clash).write_text("the user's own, same name\n")
    before = snapshot(folder)

    code, err = invoke(*args(folder, folder))
    assert code == 2, err
    assert "Traceback" not in err  # (run prints its notes before it writes)
    assert [line for line in err.splitlines() if not line.startswith("note: ")] == [f"error: {folder}: {clash} exists and rbhyst did not write it (not listed in "
                                f"{MANIFEST}); rbhyst will not overwrite it: move it away or choose another "
                                "output folder"]
    assert snapshot(folder) == before and entries(folder) == set(before)  # nothing written, no hidden folder

    (folder / clash).unlink()
    del before[clash]
    for _ in range(2):  # the second time replaces its own files
        code, err = invoke(*args(folder, folder))
        assert code == 0, err
        assert {k: v for k, v in snapshot(folder).items() if k in before} == before
        assert entries(folder) == set(before) | outputs | {MANIFEST}
        assert manifest_files(folder) == outputs
    assert no_staging_left(tmp_path)


@pytest.mark.parametrize("command", COMMANDS)
def test_an_interrupted_command_leaves_the_earlier_results(tmp_path, monkeypatch, command):
    """KeyboardInterrupt once the command has written its files, before they move in."""
    args, outputs, _ = COMMANDS[command]
    folder = user_folder(tmp_path)
    out = folder / "out"
    assert invoke(*args(folder, out))[0] == 0
    before = snapshot(folder)
    real = rbhyst.files.outdir.staged_directory

    @contextmanager
    def interrupted(target):
        with real(target) as tmp:
            yield tmp
            assert {p.name for p in tmp.iterdir()} == outputs  # all written, none moved in yet
            raise KeyboardInterrupt

    monkeypatch.setattr(rbhyst.files.outdir, "staged_directory", interrupted)
    code, _ = invoke(*args(folder, out))
    assert code == 130  # typer's exit status for KeyboardInterrupt
    assert snapshot(folder) == before and entries(folder) == set(before) | {"out"}
    fresh = tmp_path / "new" / "out"
    assert invoke(*args(folder, fresh))[0] == 130
    assert not (tmp_path / "new").exists()  # the folders it made are gone again
    assert no_staging_left(tmp_path)


def test_run_with_out_dot_and_directory_dot(tmp_path, monkeypatch):
    folder = user_folder(tmp_path)
    before = snapshot(folder)
    monkeypatch.chdir(folder)
    code, err = invoke("run", "deck.toml", "--no-plots", "--out", ".")
    assert code == 0, err
    assert entries(folder) == set(before) | {"time_history.csv", "summary.json", MANIFEST}
    assert {k: v for k, v in snapshot(folder).items() if k in before} == before
    assert entries(tmp_path) == {"work"} | {f"work/{e}" for e in entries(folder)}  # nothing beside it

    data = seed_deck(duration=0.1)
    data["output"] = {"directory": ".", "plots": False}
    write_deck(folder, data, name="dot")
    before = snapshot(folder)
    monkeypatch.chdir(tmp_path)
    code, err = invoke("run", folder / "dot.toml")
    assert code == 0, err
    assert "Traceback" not in err
    assert {k: v for k, v in snapshot(folder).items() if k not in ("time_history.csv", "summary.json", MANIFEST)} \
        == {k: v for k, v in before.items() if k not in ("time_history.csv", "summary.json", MANIFEST)}
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["analysis"]["steps"] == 100  # the second deck's
    assert entries(tmp_path) == {"work"} | {f"work/{e}" for e in entries(folder)}

    monkeypatch.chdir(folder)  # the study's default folder is beside the run's: here beside "."
    code, err = invoke("study", "dot.toml", "--integrators", "chang", "--dt", "0.002")
    assert code == 0, err
    assert entries(tmp_path / "work-study") == {"study.csv", "study.json", MANIFEST}
    assert no_staging_left(tmp_path)


def test_a_second_run_removes_its_stale_plots_only(tmp_path):
    folder = user_folder(tmp_path)
    deck = write_deck(folder, seed_deck(duration=0.05))
    (folder / "my_plot.png").write_bytes(b"\x89PNG the user's\n")
    before = snapshot(folder)
    code, err = invoke("run", deck, "--out", folder)
    assert code == 0, err
    pngs = {p.name for p in folder.glob("*.png")} - {"my_plot.png"}
    assert {"model.png", "energy.png", "element_loops.png"} <= pngs
    assert manifest_files(folder) == pngs | {"time_history.csv", "summary.json"}

    code, err = invoke("run", deck, "--out", folder, "--no-plots")
    assert code == 0, err
    assert entries(folder) == set(before) | {"time_history.csv", "summary.json", MANIFEST}
    assert snapshot(folder)["my_plot.png"] == before["my_plot.png"]
    assert {k: v for k, v in snapshot(folder).items() if k in before} == before
    assert manifest_files(folder) == {"time_history.csv", "summary.json"}


def test_make_record_writes_atomically_and_only_over_its_own_files(tmp_path, monkeypatch):
    folder = user_folder(tmp_path)
    (folder / "rec.csv").write_text("0,1\n0.01,2\n")  # the user's record
    before = snapshot(folder)
    opts = ["--duration", "2", "--dt", "0.01"]
    code, err = invoke("make-record", folder / "rec.csv", *opts)
    assert code == 2
    assert err.splitlines() == [f"error: {folder / 'rec.csv'}: exists and rbhyst did not write it (its first line "
                                f"is not '{RECORD_MARK} ...'); rbhyst will not overwrite it: move it away or "
                                "choose another name"]
    assert snapshot(folder) == before
    for name in ("deck.toml", "notes.txt"):
        assert invoke("make-record", folder / name, *opts)[0] == 2
    assert invoke("make-record", folder, *opts)[0] == 2  # a folder is not a file name
    assert snapshot(folder) == before

    out = folder / "new.csv"
    assert invoke("make-record", out, *opts, "--pga", "0.2", "--seed", "7")[0] == 0
    lines = out.read_text().splitlines()
    assert lines[0] == f"{RECORD_MARK} --duration 2.0 --dt 0.01 --pga 0.2 --units g --seed 7 --f-g 2.5"
    assert lines[1] == "time_s,acceleration_g" and len(lines) == 2 + 201
    series = read_table(out).series
    assert (series.dt, len(series.values)) == (pytest.approx(0.01), 201)
    assert np.max(np.abs(series.values)) == pytest.approx(0.2, rel=1e-7)
    assert invoke("make-record", out, *opts, "--pga", "0.3")[0] == 0  # its own: replaced
    assert read_table(out).series.values.max() != series.values.max()
    mine = out.read_bytes()

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(rbhyst.files.outdir.os, "replace", interrupted)
    assert invoke("make-record", out, *opts, "--seed", "8")[0] == 130
    assert invoke("make-record", tmp_path / "new" / "r.csv", *opts)[0] == 130
    monkeypatch.undo()
    assert out.read_bytes() == mine
    assert {k: v for k, v in snapshot(folder).items() if k != "new.csv"} == before
    assert entries(folder) == set(before) | {"new.csv"}  # no temporary file left
    assert not (tmp_path / "new").exists()


def long_deck(folder: Path) -> Path:
    """A few seconds of stepping and writing (1,000,000 steps) and no notes on stderr."""
    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 2.0, "frequency_hz": 2.5,
                                             "units": "m/s2"}}}
    data["analysis"] = {"dt": 1e-4, "duration": 100.0}
    data["output"] = {"directory": ".", "plots": False}
    return write_deck(folder, data, name="long")


@pytest.mark.parametrize("signum, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)],
                         ids=["SIGTERM", "SIGINT"])
def test_a_signal_mid_write_leaves_nothing_partial(tmp_path, signum, status):
    folder = tmp_path / "work"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine\n")
    deck = long_deck(folder)
    assert invoke("run", deck, "--dt", "0.01")[0] == 0  # earlier results, 1000 steps
    before = snapshot(folder)
    proc = subprocess.Popen([sys.executable, "-m", "rbhyst", "run", deck.name], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not any(p.name.startswith(STAGING_PREFIX) for p in folder.iterdir()):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.005)
        time.sleep(0.05)  # well into time_history.csv
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == status, err
    assert err.splitlines() == ["interrupted: nothing written"]
    assert snapshot(folder) == before and entries(folder) == set(before)


def test_staged_subfolders_and_what_the_manifest_can_name(tmp_path):
    target = tmp_path / "out"
    with staged_directory(target) as tmp:
        (tmp / "plots").mkdir()
        (tmp / "plots" / "a.png").write_text("a")
        (tmp / "table.csv").write_text("1")
    assert read_manifest(target).files == {"plots/a.png", "table.csv"}
    assert read_manifest(target).folders == {"plots"}
    (target / "plots" / "mine.txt").write_text("mine")
    with staged_directory(target) as tmp:
        (tmp / "table.csv").write_text("2")
    assert entries(target) == {"plots", "plots/mine.txt", "table.csv", MANIFEST}
    assert read_manifest(target).folders == set()

    # a manifest naming files outside the folder (or the manifest itself) cannot make rbhyst touch them
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    (target / MANIFEST).write_text(json.dumps({"rbhyst_manifest": 1, "folders": [], "files": [
        "../victim.txt", str(victim), "./table.csv", MANIFEST, "plots/mine.txt/..", "table.csv"]}))
    with staged_directory(target) as tmp:
        (tmp / "other.csv").write_text("3")
    assert victim.read_text() == "keep"
    assert entries(target) == {"plots", "plots/mine.txt", "other.csv", MANIFEST}

    # a file in the way of a subfolder, an unreadable manifest, a target that is a file
    (target / "plots" / "mine.txt").unlink()
    (target / "plots").rmdir()
    (target / "plots").write_text("not a folder")
    with pytest.raises(InputError, match=r"rbhyst would write plots/b.png, but plots is in the way"):
        with staged_directory(target) as tmp:
            (tmp / "plots").mkdir()
            (tmp / "plots" / "b.png").write_text("b")
    (target / MANIFEST).write_text("{not json")
    before = snapshot(target)
    with pytest.raises(InputError, match=r"\.rbhyst\.json: not a manifest"):
        with staged_directory(target) as tmp:
            pass
    with pytest.raises(InputError, match="exists and is not a folder"):
        with staged_directory(target / "other.csv") as tmp:
            pass
    assert snapshot(target) == before and no_staging_left(tmp_path)


def test_a_signal_during_the_commit_waits_for_it(tmp_path, monkeypatch, capsys):
    """SIGTERM while files move in: all of them move in, then the command ends (143) saying so."""
    from rbhyst.cli import main

    real = os.replace
    moves = []

    def replace_then_signal(src, dst):
        if not moves:
            signal.raise_signal(signal.SIGTERM)  # held: the Python handler would raise right here
        moves.append(Path(dst).name)
        real(src, dst)

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    target = tmp_path / "out"
    monkeypatch.setattr(rbhyst.files.outdir.os, "replace", replace_then_signal)
    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            with staged_directory(target) as tmp:
                for name in ("a.csv", "b.csv", "c.csv"):
                    (tmp / name).write_text(name)
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert moves == [MANIFEST, "a.csv", "b.csv", "c.csv", MANIFEST]
    assert entries(target) == {"a.csv", "b.csv", "c.csv", MANIFEST}
    assert manifest_files(target) == {"a.csv", "b.csv", "c.csv"}

    moves.clear()
    out = tmp_path / "rec.csv"
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    monkeypatch.setattr(sys, "argv", ["rbhyst", "make-record", str(out), "--duration", "1"])
    try:
        with pytest.raises(SystemExit) as exc:
            main()
    finally:
        for s, h in handlers.items():
            signal.signal(s, h)
    assert exc.value.code == 143
    assert capsys.readouterr().err.splitlines()[-1] == f"interrupted after writing {out}"
    assert out.read_text().startswith(RECORD_MARK) and len(out.read_text().splitlines()) == 2 + 101
