"""A sweep's store proves its contents: a journal line cut short or altered after it was
written, or a histories file changed, is named in one note, set aside and computed again, so
that cases.csv never holds a number rbhyst did not compute."""

from __future__ import annotations

import json

import pytest

from rbhyst.sweep import load_sweep
from rbhyst.analyses.sweep.store import FOLDER, HISTORIES, JOURNAL, line_sum
from conftest import invoke
from test_sweep import basic, project, read_cases, write_sweep  # noqa: F401  (the fixture)


def finished(project, *args):
    sweep = write_sweep(project, basic(duration=0.5))
    code, err = invoke("sweep", sweep, "--workers", "2", "--no-plots", *args)
    assert code == 0, err
    out = project / "results" / "sweep"
    return sweep, out, out / FOLDER / JOURNAL


def line_of(journal, number: int, sweep) -> int:
    """The index in the journal's lines of the line of case ``number``."""
    key = load_sweep(sweep).cases[number - 1].key
    lines = journal.read_bytes().split(b"\n")
    return next(i for i, ln in enumerate(lines) if i and ln and json.loads(ln)["key"] == key)


def notes(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if ln.startswith("note:") and "compiling" not in ln]


def test_every_line_carries_the_checksum_of_its_content(project):
    _, _, journal = finished(project)
    lines = journal.read_bytes().splitlines()
    assert json.loads(lines[0])["rbhyst_sweep_journal"] == 2
    for ln in lines[1:]:
        e = json.loads(ln)
        assert e["sha256"] == line_sum(e) and len(e["sha256"]) == 64


def test_a_cut_line_and_an_edited_peak_are_named_and_computed_again(project):
    sweep, out, journal = finished(project)
    before = read_cases(out / "cases.csv")
    lines = journal.read_bytes().split(b"\n")
    cut, edited = line_of(journal, 3, sweep), line_of(journal, 6, sweep)
    lines[cut] = lines[cut][: len(lines[cut]) // 2]  # cut short in the middle of the file
    e = json.loads(lines[edited])
    e["peaks"]["u1_m"] *= 1.5  # a number changed by hand, its checksum left as it was
    lines[edited] = json.dumps(e).encode()
    journal.write_bytes(b"\n".join(lines))

    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0, err
    said = notes(err)
    assert len(said) == 1, err
    assert said[0].startswith("note: the store could not vouch for 2 finished cases, computed again: case 3 (")
    assert "case 3 (line " in said[0] and "damaged: cut short or edited" in said[0]
    assert "case 6 (line " in said[0] and "altered after it was written" in said[0]
    assert "computed 2 on " in err and "6 already in the folder" in err
    assert read_cases(out / "cases.csv") == before  # the edited peak is gone, the computed one back
    # the journal was rewritten without them: the next run trusts everything and says nothing
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0 and not notes(err) and "computed 0, 8 already" in err, err
    assert read_cases(out / "cases.csv") == before


def test_an_interrupted_append_is_told_apart_by_its_wording(project):
    sweep, out, journal = finished(project)
    before = read_cases(out / "cases.csv")
    data = journal.read_bytes()
    last = data[:-1].rsplit(b"\n", 1)
    journal.write_bytes(last[0] + b"\n" + last[1][:50])  # the last append stopped after 50 bytes
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0, err
    said = notes(err)
    assert len(said) == 1 and "(cut short by an interrupted write)" in said[0], err
    assert "computed 1 on " in err and "7 already" in err
    assert read_cases(out / "cases.csv") == before
    assert journal.read_bytes().endswith(b"\n")


def test_a_line_too_short_to_name_its_case_is_counted(project):
    sweep, out, journal = finished(project)
    data = journal.read_bytes()
    journal.write_bytes(data + b'{"ke\n{"k')
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0, err
    assert notes(err) == ["note: the store had 2 damaged lines of no case of this sweep (set aside)"], err
    assert "computed 0, 8 already" in err
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0 and not notes(err)


def test_a_journal_of_an_earlier_rbhyst_without_checksums_is_not_trusted(project):
    sweep, out, journal = finished(project)
    lines = journal.read_bytes().splitlines()
    mark = json.loads(lines[0])
    mark["rbhyst_sweep_journal"] = 1
    old = [json.dumps(mark).encode()] + [json.dumps({k: v for k, v in json.loads(ln).items() if k != "sha256"}).encode()
                                        for ln in lines[1:]]
    journal.write_bytes(b"\n".join(old) + b"\n")
    code, err = invoke("sweep", sweep, "--no-plots")
    assert code == 0, err
    said = notes(err)
    assert len(said) == 1 and "8 finished cases" in said[0] and "3 more" in said[0], err
    assert "kept by an earlier rbhyst without a checksum" in said[0]
    assert "computed 8 on " in err and "0 already" in err


def test_an_altered_histories_file_is_computed_again(project):
    pytest.importorskip("pyarrow")
    sweep, out, journal = finished(project, "--save-histories")
    entries = [json.loads(ln) for ln in journal.read_bytes().splitlines()[1:]]
    name = entries[0]["history"]
    sharing = sum(e.get("history") == name for e in entries)
    part = out / FOLDER / HISTORIES / name
    data = bytearray(part.read_bytes())
    data[len(data) // 2] ^= 0xFF
    part.write_bytes(bytes(data))
    code, err = invoke("sweep", sweep, "--no-plots", "--save-histories")
    assert code == 0, err
    said = notes(err)
    assert len(said) == 1 and f"its histories file {HISTORIES}/{name} was altered after it was written" in said[0]
    assert f"computed {sharing} on " in err and f"{8 - sharing} already" in err


def test_the_cases_held_compact_are_the_cases_written(tmp_path):
    """The store holds each case's numbers as Numbers (an array, the names shared with every case
    of the same names): they read as the dicts written (None as None, not nan), their journal
    lines and checksums are the dicts' byte for byte, a group holding anything but floats stays
    a dict, and a journal read again gives the same entries."""
    from rbhyst.analyses.sweep.store import Journal, Numbers, _entry_line, kept_sum

    def entry(k: int) -> dict:
        return {"key": f"{k:032x}", "status": "ok", "message": "", "wall_s": 0.5,
                "peaks": {"u1": 0.001 * k, "R3": None, "at2": -0.0},
                "energy": {"E_in_J": 1.5 + k}, "accuracy": {"u1": 1e-3, "n": 3},
                "stroke": {}}

    plain = [entry(k) for k in range(4)]
    lines = [_entry_line(e) for e in plain]
    sums = [line_sum(e) for e in plain]
    journal = Journal(tmp_path / "out")
    journal.add([entry(k) for k in range(4)])
    journal.close()
    for k, again in enumerate((journal.entries, Journal(tmp_path / "out").entries)):
        held = list(again.values())
        assert [_entry_line(e) for e in held] == lines and [line_sum(e) for e in held] == sums
        assert [kept_sum(e) for e in held] == sums  # (the sum the journal keeps: what outputs_sum takes)
        for e, p in zip(held, plain):
            assert isinstance(e["peaks"], Numbers) and isinstance(e["energy"], Numbers)
            assert dict(e["peaks"]) == p["peaks"] and e["peaks"]["R3"] is None and e["peaks"].get("x") is None
            assert str(e["peaks"]["at2"]) == "-0.0" and type(e["peaks"]["u1"]) is float
            assert e["accuracy"] == p["accuracy"] and type(e["accuracy"]) is dict  # (an int in it: as it is)
        assert held[0]["peaks"]._index is held[3]["peaks"]._index  # (one index of the names for all)
        # (and one copy of each key's string and of the status, where each line had its own)
        keys = [{k: k for k in e} for e in held]
        assert all(keys[0][k] is keys[3][k] for k in keys[0]) and held[0]["status"] is held[3]["status"]
