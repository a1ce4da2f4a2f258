import numpy as np
import pytest

from rbhyst.errors import InputError
from rbhyst.model.records import read_at2, read_series, read_table
from conftest import DECKS, records_or_skip


def test_el_centro_at2_header_and_values():
    folder = records_or_skip()
    s = read_at2(folder / "I-ELC180.AT2").series
    assert s.dt == 0.01 and len(s.values) == 4000
    assert np.max(np.abs(s.values)) == pytest.approx(0.3129, abs=5e-5)
    assert s.values[0] == pytest.approx(-0.6403182e-02)  # real records rarely start at zero
    s270 = read_at2(folder / "I-ELC270.AT2").series
    assert np.max(np.abs(s270.values)) == pytest.approx(0.2148, abs=5e-5)


def test_at2_older_header_layout(tmp_path):
    p = tmp_path / "old.at2"
    p.write_text("PEER STRONG MOTION DATABASE RECORD\nSOMEWHERE\nACCELERATION TIME HISTORY IN UNITS OF G\n"
                 "   5    0.0200    NPTS, DT\n 0.1 0.2 0.3\n 0.4 0.5\n")
    s = read_series(p)
    assert s.dt == 0.02
    np.testing.assert_allclose(s.values, [0.1, 0.2, 0.3, 0.4, 0.5])
    np.testing.assert_allclose(s(np.array([0.01, 0.07, 0.08, 0.09])), [0.15, 0.45, 0.5, 0.0])


def test_two_columns_with_header_and_one_column_with_dt(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("time_s,acc\n0.0,1.0\n0.5,2.0\n1.0,0.0\n")
    s = read_table(p).series
    assert (s.t0, s.dt) == (0.0, 0.5)
    q = tmp_path / "b.txt"
    q.write_text("1.0\n2.0\n0.0\n")
    s = read_table(q, dt=0.5).series
    np.testing.assert_allclose(s(np.array([0.25, 0.75])), [1.5, 1.0])


@pytest.mark.parametrize("text, words", [
    ("time,acc\n0,1\n0.1,nan\n", "not a finite number"),
    ("0,1\n0.1,abc\n", "not a number"),
    ("0,1\n0.1,2,3\n", "3 columns"),
    ("0,1\n0.1,2\n0.3,2\n", "not uniform"),
    ("0,1\n0.1,2\n0.1,3\n", "does not increase"),
    ("0,1\n", "at least two rows"),
    ("   \n\n", "empty"),
])
def test_bad_tables(tmp_path, text, words):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=words):
        read_table(p)


def test_one_column_needs_dt_and_at2_header_is_checked(tmp_path):
    p = tmp_path / "one.csv"
    p.write_text("1\n2\n3\n")
    with pytest.raises(InputError, match="needs `dt`"):
        read_table(p)
    q = tmp_path / "broken.at2"
    q.write_text("HEADER\nNO COUNTS HERE\n0.1 0.2\n")
    with pytest.raises(InputError, match="NPTS"):
        read_series(q)
    r = tmp_path / "short.at2"
    r.write_text("NPTS=  4, DT= .01 SEC\n0.1 0.2 0.3\n")
    with pytest.raises(InputError, match="NPTS=4 but the file holds 3"):
        read_series(r)


def test_shipped_synthetic_records_are_reproducible(tmp_path):
    from typer.testing import CliRunner

    from rbhyst.cli import app

    for name, pga, seed in (("synthetic_x1.csv", "0.35", "1"), ("synthetic_x2.csv", "0.25", "2")):
        out = tmp_path / name
        res = CliRunner().invoke(app, ["make-record", str(out), "--pga", pga, "--seed", seed])
        assert res.exit_code == 0, res.output
        assert out.read_text() == (DECKS / "records" / name).read_text()
