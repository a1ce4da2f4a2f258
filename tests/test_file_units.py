"""Units a record file declares (AT2 header, CSV column labels) against the deck's `units`."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from rbhyst.cli import app
from rbhyst.errors import InputError
from rbhyst.files.units import at2_declarations, check_declared, header_labels, label_unit
from rbhyst.model.records import read_record
from conftest import DECKS, records_or_skip, seed_deck, write_deck

runner = CliRunner()
G = 9.80665


def run(*args):
    res = runner.invoke(app, [str(a) for a in args])
    return res.exit_code, res.stdout, res.stderr


def run_x1(tmp_path: Path, x1: dict, name: str = "deck", duration: float = 1.0):
    """The seed scene with support x1 replaced; returns (exit code, stderr, output folder)."""
    data = copy.deepcopy(seed_deck(duration=duration))
    data["excitation"]["support"]["x1"] = x1
    out = tmp_path / f"out_{name}"
    code, _, err = run("run", write_deck(tmp_path, data, name=name), "--out", out, "--no-plots")
    return code, err, out


def one_error_line(code, err, out) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    assert not out.exists()
    return lines[0][len("error: "):]


def summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


AT2_OLD = ("PEER STRONG MOTION DATABASE RECORD\nSOMEWHERE, 1999\nACCELERATION TIME HISTORY IN {units}\n"
           "   6    0.0100    NPTS, DT\n 0.1 -0.25 0.3\n 0.4 -0.5 0.2\n")


# ---------------------------------------------------------------- reading declarations


@pytest.mark.parametrize("label, unit", [
    ("acc_g", "g"), ("acceleration_g", "g"), ("acceleration_m_s2", "m/s2"), ("acceleration_cm_s2", "cm/s2"),
    ("a [m/s2]", "m/s2"), ("a (cm/s^2)", "cm/s2"), ("ag_mps2", "m/s2"), ("a [gal]", "cm/s2"),
    ("acc [m s^-2]", "m/s2"), ("f_kN", "kN"), ("force [N]", "N"), ("m3_kN_m", "kN m"), ("M (N m)", "N m"),
    ("time_s", "s"), ("t [s]", "s"), ("time_ms", "ms"), ("t [ms]", "ms"), ("time [min]", "min"),
    ("t (us)", "us"), ("a_mg", "mg"),
])
def test_column_labels_that_declare_a_unit(label, unit):
    assert label_unit(label)[1].name == unit


@pytest.mark.parametrize("label", ["acc", "acceleration", "acc_x", "time", "a_n", "acc_kn", "a (filtered)"])
def test_column_labels_that_declare_nothing(label):
    assert label_unit(label)[1] is None


def test_header_labels_keep_bracketed_units_with_their_names():
    assert header_labels("t [s]   a [m/s2]") == ["t [s]", "a [m/s2]"]
    assert header_labels('"time_s"; "acc_g"') == ["time_s", "acc_g"]
    assert header_labels("a(t) [g] x") == ["a(t) [g]", "x"]


@pytest.mark.parametrize("line, unit", [
    ("ACCELERATION TIME HISTORY IN UNITS OF G. FILTER POINTS: HP=0.2 Hz LP=15.0 Hz", "g"),
    ("ACCELERATION TIME SERIES IN UNITS OF G", "g"), ("Acceleration in g", "g"),
    ("ACCEL IN CM/S/S", "cm/s2"), ("UNITS: CM/SEC/SEC", "cm/s2"), ("corrected accel cm/s^2", "cm/s2"),
    ("DATA IN GAL", "cm/s2"), ("ACCELERATION M/S/S", "m/s2"), ("accel (m/s2)", "m/s2"),
    ("ACCELERATION IN UNITS OF G (1 G = 980.665 CM/S/S)", "g"),
    ("VELOCITY TIME HISTORY IN UNITS OF CM/S", "cm/s"),
])
def test_at2_header_phrases(line, unit):
    found = at2_declarations(["PEER STRONG MOTION DATABASE RECORD", line])
    assert [(i, u.name) for i, _, u in found] == [(1, unit)]


@pytest.mark.parametrize("line", ["IMPERIAL VALLEY 5/19/40 0439, EL CENTRO ARRAY #9, 180 (USGS STATION 117)",
                                  "RECORDED IN GILROY (N) 1989", "COMPONENT N/S"])
def test_at2_station_lines_declare_nothing(line):
    assert at2_declarations([line]) == []


def test_make_record_headers_declare_their_units(tmp_path):
    for units in ("g", "m/s2", "cm/s2"):
        out = tmp_path / f"rec_{units.replace('/', '')}.csv"
        code, _, err = run("make-record", out, "--duration", 0.5, "--units", units)
        assert code == 0, err
        assert read_record(out).declared.unit.name == units


def test_check_names_both_units_and_both_kinds(tmp_path):
    p = tmp_path / "f.csv"
    p.write_text("time_s,f_N\n0,1\n0.1,2\n")
    declared = read_record(p).declared
    check_declared(declared, "N")
    with pytest.raises(InputError) as err:
        check_declared(declared, "g")
    assert err.value.problems == [f"{p}:1: the header declares 'f_N' (N, a force) "
                                  'but the deck says units = "g" (an acceleration)']


# ---------------------------------------------------------------- AT2 files in a run


def test_el_centro_in_g_refused_under_m_s2_and_right_under_g(tmp_path):
    rec = records_or_skip() / "I-ELC180.AT2"
    code, err, out = run_x1(tmp_path, {"file": str(rec), "units": "m/s2"}, "ms2")
    assert one_error_line(code, err, out) == (
        f"excitation.support.x1: {rec}:3: the header declares 'UNITS OF G' (g) but the deck says units = \"m/s2\"")
    # under g: the run's support acceleration peaks where the record does (0.3129 g at 2.15 s)
    code, err, out = run_x1(tmp_path, {"file": str(rec), "units": "g"}, "g", duration=2.5)
    assert code == 0, err
    lines = rec.read_text().splitlines()
    values = np.array([float(x) for line in lines[4:] for x in line.split()])
    assert summary(out)["peaks"]["ag1_m_s2"] == pytest.approx(np.max(np.abs(values[:251])) * G, rel=1e-12)
    assert summary(out)["peaks"]["ag1_m_s2"] == pytest.approx(0.3128806 * G, rel=1e-12)


def test_at2_in_cm_s2_refused_under_g_and_read_under_cm_s2(tmp_path):
    (tmp_path / "cms2.at2").write_text(AT2_OLD.format(units="UNITS OF CM/S/S"))
    code, err, out = run_x1(tmp_path, {"file": "cms2.at2", "units": "g"}, "g")
    assert one_error_line(code, err, out) == (
        f"excitation.support.x1: {tmp_path / 'cms2.at2'}:3: the header declares 'UNITS OF CM/S/S' (cm/s2) "
        'but the deck says units = "g"')
    code, err, out = run_x1(tmp_path, {"file": "cms2.at2", "units": "cm/s2"}, "cms2")
    assert code == 0, err
    assert summary(out)["peaks"]["ag1_m_s2"] == 0.5 * 0.01


def test_at2_velocity_under_an_acceleration_is_refused(tmp_path):
    (tmp_path / "v.at2").write_text(AT2_OLD.format(units="UNITS OF CM/S"))
    code, err, out = run_x1(tmp_path, {"file": "v.at2", "units": "cm/s2"})
    assert one_error_line(code, err, out).endswith(
        "the header declares 'UNITS OF CM/S' (cm/s, a velocity) but the deck says units = \"cm/s2\" (an acceleration)")


def test_at2_with_two_different_units_is_refused(tmp_path):
    (tmp_path / "two.at2").write_text(AT2_OLD.format(units="G\nACCEL IN CM/S/S"))
    code, err, out = run_x1(tmp_path, {"file": "two.at2", "units": "g"})
    assert "the header declares both 'IN G' (g, line 3) and 'IN CM/S/S' (cm/s2)" in one_error_line(code, err, out)


# ---------------------------------------------------------------- tables in a run


def test_csv_in_g_refused_under_m_s2(tmp_path):
    (tmp_path / "x1.csv").write_text("time_s,acc_g\n0,0.1\n0.01,0.2\n0.02,0.0\n")
    code, err, out = run_x1(tmp_path, {"file": "x1.csv", "units": "m/s2"})
    assert one_error_line(code, err, out) == (
        f"excitation.support.x1: {tmp_path / 'x1.csv'}:1: the header declares 'acc_g' (g) "
        'but the deck says units = "m/s2"')


#: a record step exact in binary (60/1024 s), so that its times written in any of these
#: units are exact too, and both files give the same times to the last bit
STEP_S = 0.05859375


@pytest.mark.parametrize("label, unit, time_text", [
    ("time_ms", "ms", lambda k: f"{k * STEP_S * 1000:.5f}"),
    ("t [us]", "us", lambda k: f"{k * STEP_S * 1e6:.2f}"),
    ("time [min]", "min", lambda k: f"{k / 1024:.10f}"),
])
def test_time_column_in_other_units_gives_the_same_run_as_in_seconds(tmp_path, label, unit, time_text):
    k = np.arange(20)
    rows = [f"{v:.8e}\n" for v in 0.3 * np.sin(2 * np.pi * 2.0 * STEP_S * k)]
    (tmp_path / "s.csv").write_text("time_s,acc_g\n" + "".join(f"{i * STEP_S:.8f},{r}" for i, r in zip(k, rows)))
    (tmp_path / "u.csv").write_text(f"{label},acc_g\n" + "".join(f"{time_text(i)},{r}" for i, r in zip(k, rows)))
    code, err, out_s = run_x1(tmp_path, {"file": "s.csv", "units": "g"}, "s")
    assert code == 0, err
    code, err, out_u = run_x1(tmp_path, {"file": "u.csv", "units": "g"}, "u")
    assert code == 0, err
    assert (out_u / "time_history.csv").read_text() == (out_s / "time_history.csv").read_text()
    assert summary(out_u)["peaks"] == summary(out_s)["peaks"]
    assert f"excitation.support.x1: time column '{label}' converted from {unit} to s" in summary(out_u)["notes"]
    assert not any("converted" in note for note in summary(out_s)["notes"])


def test_minutes_become_seconds(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("time [min],a [g]\n1.0,0.1\n1.5,0.2\n2.0,0.3\n")
    rec = read_record(p)
    assert (rec.series.t0, rec.series.dt, rec.series.duration) == (60.0, 30.0, 120.0)
    assert rec.notes == ("time column 'time [min]' converted from min to s",)


@pytest.mark.parametrize("header, expected", [
    ("t [fortnight],acc_g", "the time column 't [fortnight]': 'fortnight' is not a time unit; "
                            "use one of s, ms, us, ns, min, hr"),
    ("t [g],acc_g", "the time column 't [g]': 'g' is an acceleration unit"),
    ("time_s,acc_g,station", "the header names 3 columns but the rows hold 2"),
])
def test_unreadable_time_units_are_refused(tmp_path, header, expected):
    (tmp_path / "x1.csv").write_text(header + "\n0,0.1\n0.01,0.2\n0.02,0.0\n")
    code, err, out = run_x1(tmp_path, {"file": "x1.csv", "units": "g"})
    line = one_error_line(code, err, out)
    assert line.startswith(f"excitation.support.x1: {tmp_path / 'x1.csv'}:1: ") and expected in line


@pytest.mark.parametrize("header", ["time,acceleration", "t a", "time_s,acc (station 5)", "time_x,acc_y"])
def test_a_header_without_units_takes_the_deck_units(tmp_path, header):
    (tmp_path / "x1.csv").write_text(header + "\n0,0.1\n0.01,-0.25\n0.02,0.0\n")
    code, err, out = run_x1(tmp_path, {"file": "x1.csv", "units": "cm/s2"})
    assert code == 0, err
    assert summary(out)["peaks"]["ag1_m_s2"] == 0.25 * 0.01


def test_force_files_are_checked_against_force_units(tmp_path):
    data = copy.deepcopy(seed_deck(duration=0.5))
    (tmp_path / "p1.csv").write_text("time_s,f_kN\n0,1.0\n0.01,2.0\n0.02,0.0\n")
    (tmp_path / "m3.csv").write_text("time_s,m3_kN_m\n0,0.5\n0.01,1.0\n0.02,0.0\n")
    data["excitation"]["force"] = {"p1": {"file": "p1.csv", "units": "N"}, "m3": {"file": "m3.csv", "units": "kN m"}}
    out = tmp_path / "out"
    code, _, err = run("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert one_error_line(code, err, out) == (
        f"excitation.force.p1: {tmp_path / 'p1.csv'}:1: the header declares 'f_kN' (kN) "
        'but the deck says units = "N"')
    data["excitation"]["force"]["p1"]["units"] = "kN"
    code, _, err = run("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0, err


def test_a_force_file_under_a_support_acceleration_is_refused(tmp_path):
    (tmp_path / "f.csv").write_text("time_s,force [N]\n0,1.0\n0.01,2.0\n0.02,0.0\n")
    code, err, out = run_x1(tmp_path, {"file": "f.csv", "units": "m/s2"})
    assert one_error_line(code, err, out).endswith(
        "the header declares 'force [N]' (N, a force) but the deck says units = \"m/s2\" (an acceleration)")


def test_seed_deck_records_still_run(tmp_path):
    data = copy.deepcopy(seed_deck(duration=1.0))
    for axis in ("x1", "x2"):
        rec = DECKS / "records" / f"synthetic_{axis}.csv"
        assert "time_s,acceleration_g" in rec.read_text().splitlines()[:2]
        data["excitation"]["support"][axis] = {"file": str(rec), "units": "g"}
    out = tmp_path / "out"
    code, _, err = run("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 0, err
    values = np.loadtxt(DECKS / "records" / "synthetic_x1.csv", delimiter=",", comments="#", skiprows=2)[:101, 1]
    assert summary(out)["peaks"]["ag1_m_s2"] == pytest.approx(np.max(np.abs(values)) * G, rel=1e-12)
