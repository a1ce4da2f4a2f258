"""Response spectra of a run ([output.spectra]) and of a record alone (rbhyst spectrum).

The oscillators themselves are tested in test_spectra.py; what a run adds is which
accelerations reach them: the ground's must give exactly the record's spectrum, G's and the
points' exactly those of their columns, at every step of dt whatever output.every writes
and however the rows are chunked.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

import rbhyst
import rbhyst.solve.plan
from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.errors import InputError
from rbhyst.response import response_spectrum
from rbhyst.solve.located import SPECTRA_COLUMNS, rest_samples
from rbhyst.analyses.record_spectrum import record_spectrum
from rbhyst.model.synthetic import ground_motion
from conftest import seed_deck, write_deck

G = 9.80665
DT = 0.002
PERIODS = [0.004, 0.02, 0.1, 0.3, 1.0, 3.0]  # 0.004 s: below 20 dt, so the oscillators take substeps
DAMPINGS = [0.05, 0.02]


@pytest.fixture
def record_deck(tmp_path):
    """The seed scene under a 1.5 s synthetic record along x1 only: one column, its dt the run's."""
    _, acc = ground_motion(duration=1.5, dt=DT, pga=0.3, seed=3)
    np.savetxt(tmp_path / "x1.csv", acc, header="acc_g", comments="")
    d = seed_deck(duration=1.5)
    d["excitation"] = {"support": {"x1": {"file": "x1.csv", "units": "g", "dt": DT}}}
    d["analysis"]["dt"] = DT
    d["output"] = {"points": [{"name": "top", "point": [-0.1286, 1.0571]}],
                   "spectra": {"damping": DAMPINGS, "periods_s": PERIODS}}
    return tmp_path, d, acc * G * 1.0  # (as the run scales it: units, then `scale`)


@pytest.mark.parametrize("integrator", ["chang", "adaptive"])
def test_the_grounds_spectra_are_the_records(record_deck, integrator):
    folder, d, ag = record_deck
    res = rbhyst.run(write_deck(folder, d), integrator=integrator, estimate=False)
    assert res.spectra.signals == (("ground", "x1"), ("G", "x1"), ("G", "x2"), ("top", "x1"), ("top", "x2"))
    whole = response_spectrum(ag, DT, PERIODS, DAMPINGS)
    np.testing.assert_array_equal(res.spectra.sa("ground", "x1"), whole.sa[:, :, 0])
    np.testing.assert_array_equal(res.spectra.sd("ground", "x1"), whole.sd[:, :, 0])
    for loc, direction, column in (("G", "x1", "at1_m_s2"), ("G", "x2", "at2_m_s2"),
                                   ("top", "x1", "top_at1_m_s2"), ("top", "x2", "top_at2_m_s2")):
        own = response_spectrum(res.column(column), DT, PERIODS, DAMPINGS)
        np.testing.assert_array_equal(res.spectra.sa(loc, direction), own.sa[:, :, 0])
        np.testing.assert_array_equal(res.spectra.sd(loc, direction), own.sd[:, :, 0])
    # the body amplifies or isolates: its spectra are not the ground's (the test can tell them apart)
    assert not np.allclose(res.spectra.sa("G", "x1"), res.spectra.sa("ground", "x1"), rtol=1e-3)


def test_streamed_in_small_chunks_and_every_change_nothing(record_deck, monkeypatch):
    folder, d, _ = record_deck
    path = write_deck(folder, d)
    whole = rbhyst.run(path, estimate=False).spectra
    monkeypatch.setattr(rbhyst.solve.plan, "CHUNK_BYTES", 1)  # 64-row chunks
    d["output"]["every"] = 7
    res = rbhyst.run(write_deck(folder, d, name="every7"), out=folder / "out", plots=True, estimate=False)
    assert (folder / "out" / "spectra.png").stat().st_size > 0
    assert res.spectra.signals == whole.signals
    np.testing.assert_array_equal(res.spectra.spectrum.sa, whole.spectrum.sa)
    np.testing.assert_array_equal(res.spectra.spectrum.sd, whole.spectrum.sd)
    assert res.spectra.spectrum.samples == 751  # every step of dt, t = 0 included

    rows = list(csv.reader((folder / "out" / "spectra.csv").open()))
    assert tuple(rows[0]) == SPECTRA_COLUMNS
    assert len(rows) - 1 == 5 * len(DAMPINGS) * len(PERIODS)
    assert rows[1][:4] == ["ground", "x1", "0.05", "0.004"]
    # G, x2, damping 0.02, T = 0.3 s: the row holds that curve's numbers (10 digits)
    k = 1 + (2 * len(DAMPINGS) + 1) * len(PERIODS) + 3
    loc, direction, zeta, t, f, sa, psa, sd = rows[k]
    assert (loc, direction, float(zeta), float(t)) == ("G", "x2", 0.02, 0.3)
    i = res.spectra.index("G", "x2")
    assert float(sa) == pytest.approx(res.spectra.spectrum.sa[3, 1, i], rel=1e-9)
    assert float(sd) == pytest.approx(res.spectra.spectrum.sd[3, 1, i], rel=1e-9)
    assert float(psa) == pytest.approx((2 * np.pi / 0.3) ** 2 * float(sd), rel=1e-9)
    assert float(f) == pytest.approx(1 / 0.3, rel=1e-9)

    entry = json.loads((folder / "out" / "summary.json").read_text())["spectra"]
    assert entry["file"] == "spectra.csv" and entry["dampings"] == DAMPINGS
    assert entry["periods_s"] == {"min": 0.004, "max": 3.0, "count": 6}
    assert entry["locations"] == ["ground", "G", "top"]
    peak = next(p for p in entry["peaks"] if (p["location"], p["direction"], p["damping"]) == ("top", "x1", 0.05))
    assert peak["sa_m_s2"] == res.spectra.sa("top", "x1")[:, 0].max()


def test_a_run_without_spectra_pays_nothing_and_says_nothing(tmp_path):
    res = rbhyst.run(write_deck(tmp_path, seed_deck(duration=0.1)), out=tmp_path / "out", plots=False,
                     estimate=False)
    assert res.spectra is None and "spectra" not in res.summary()
    assert not (tmp_path / "out" / "spectra.csv").exists()


def test_rest_after_the_record_lets_every_oscillator_reach_its_peak():
    _, acc = ground_motion(duration=2.0, dt=0.01, pga=0.3, seed=5)
    periods, dampings = [0.1, 1.0, 4.0, 8.0], [0.0, 0.05, 0.3]
    n = rest_samples(periods, dampings, 0.01)
    assert n == 1 + int(np.ceil(0.5 * 8.0 / np.sqrt(1 - 0.09) / 0.01))
    enough = response_spectrum(np.concatenate([acc, np.zeros(n)]), 0.01, periods, dampings)
    longer = response_spectrum(np.concatenate([acc, np.zeros(10 * n)]), 0.01, periods, dampings)
    np.testing.assert_array_equal(enough.sa, longer.sa)
    np.testing.assert_array_equal(enough.sd, longer.sd)
    bare = response_spectrum(acc, 0.01, periods, dampings)
    assert (bare.sd[-1] < 0.9 * enough.sd[-1]).all()  # 8 s oscillators peak after a 2 s record


def test_a_run_long_enough_gives_the_records_full_spectrum_and_a_short_one_says_so(record_deck):
    folder, d, _ = record_deck
    res = rbhyst.run(write_deck(folder, d), estimate=False)
    need = 1.5 + 0.5 * 3.0 / np.sqrt(1 - 0.05**2)
    note, = [n for n in res.notes if n.startswith("output.spectra")]
    assert f"analysis.duration = {need:.4g} s" in note
    d["analysis"]["duration"] = 3.2
    res = rbhyst.run(write_deck(folder, d), estimate=False)
    assert not [n for n in res.notes if n.startswith("output.spectra")]
    alone = record_spectrum(folder / "x1.csv", "g", dt=DT, dampings=DAMPINGS, periods=PERIODS)
    np.testing.assert_array_equal(res.spectra.sa("ground", "x1"), alone.sa("ground", "x1"))
    np.testing.assert_array_equal(res.spectra.sd("ground", "x1"), alone.sd("ground", "x1"))


def test_the_spectrum_command_writes_the_records_spectra(tmp_path):
    t, acc = ground_motion(duration=1.0, dt=0.005, pga=0.25, seed=7)
    rec = tmp_path / "rec.csv"
    rec.write_text("time_s,acc_g\n" + "".join(f"{a:.6f},{b:.8e}\n" for a, b in zip(t, acc)))
    res = CliRunner().invoke(app, ["spectrum", str(rec), "--units", "g", "--damping", "0.05,0.02",
                                   "--periods", "0.1,0.02,0.5"])
    assert res.exit_code == 0, res.stderr
    out = tmp_path / "results" / "rec-spectrum"
    assert sorted(p.name for p in out.iterdir()) == [".rbhyst.json", "spectra.csv", "spectra.png"]
    rows = list(csv.reader((out / "spectra.csv").open()))
    assert tuple(rows[0]) == SPECTRA_COLUMNS and len(rows) == 1 + 2 * 3
    assert [r[3] for r in rows[1:4]] == ["0.02", "0.1", "0.5"]  # ascending periods
    t, acc = np.loadtxt(rec, delimiter=",", skiprows=1).T  # (as written: 9 digits)
    step = (t[-1] - t[0]) / (len(t) - 1)
    expect = response_spectrum(np.concatenate([acc * G, np.zeros(rest_samples([0.5], [0.05, 0.02], step))]),
                               step, [0.02, 0.1, 0.5], [0.05, 0.02])
    got = np.array([[float(v) for v in r[5:]] for r in rows[1:]])
    np.testing.assert_allclose(got[:, 0], expect.sa[:, :, 0].T.ravel(), rtol=1e-9)
    np.testing.assert_allclose(got[:, 2], expect.sd[:, :, 0].T.ravel(), rtol=1e-9)
    assert "damping 0.05: peak sa" in res.stderr


@pytest.mark.parametrize("args, lines", [
    (["--units", "m/s2"], ["error: {rec}:1: the header declares 'acc_g' (g) but --units says \"m/s2\""]),
    (["--units", "g", "--dt", "0.01"], ["error: {rec}: has a time column; leave --dt out"]),
    (["--units", "furlongs", "--damping", "1.5,0.05,0.05", "--periods", "0,1"],
     ["error: --damping: 1.5 must be at least 0 and below 1", "error: --periods: 0 s must be positive",
      "error: --damping: each damping once",
      "error: --units: 'furlongs' is not an acceleration unit rbhyst knows; choose one of g, m/s2, cm/s2"]),
])
def test_spectrum_mistakes_one_line_each(tmp_path, args, lines):
    rec = tmp_path / "rec.csv"
    rec.write_text("time_s,acc_g\n0,0\n0.01,0.1\n0.02,0\n")
    res = CliRunner().invoke(app, ["spectrum", str(rec), *args])
    assert res.exit_code == 2
    assert res.stderr.splitlines() == [line.format(rec=rec) for line in lines]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]


@pytest.mark.parametrize("spectra, lines", [
    ({"damping": [0.05, 0.05]}, ["output.spectra.damping: [0.05, 0.05]: each damping once"]),
    ({"damping": 1.0, "periods_s": [0.1, -1.0]},
     ["output.spectra.damping[1]: must be less than 1", "output.spectra.periods_s[2]: must be "
                                                                 "greater than 0"]),
    ({"periods_s": [0.1, 0.1], "dampings": 0.1},
     ["output.spectra.periods_s: each period once", "output.spectra.dampings: unknown key"]),
])
def test_spectra_mistakes_one_line_each(spectra, lines):
    d = seed_deck()
    d["output"] = {"spectra": spectra}
    with pytest.raises(InputError) as err:
        parse_deck(d)
    assert err.value.problems == lines


def test_spectra_keys_default_and_sort():
    d = seed_deck()
    d["output"] = {"spectra": {"damping": 0.02, "periods_s": [1.0, 0.1]}}
    s = parse_deck(d).output.spectra
    assert s.dampings == (0.02,) and s.periods == (0.1, 1.0)
    d["output"] = {"spectra": {}}
    s = parse_deck(d).output.spectra
    assert s.dampings == (0.05,) and len(s.periods) == 100 and s.periods[0] == 0.01 and s.periods[-1] == 10.0


def test_a_run_with_spectra_refuses_a_foreign_spectra_csv(record_deck):
    folder, d, _ = record_deck
    path = write_deck(folder, d)
    (folder / "out").mkdir()
    (folder / "out" / "spectra.csv").write_text("the user's own\n")
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(folder / "out"), "--no-plots"])
    assert res.exit_code == 2
    assert [line for line in res.stderr.splitlines() if not line.startswith("note: ")] == [
        f"error: {folder / 'out'}: spectra.csv exists and rbhyst did not write it (not listed in .rbhyst.json); "
        "rbhyst will not overwrite it: move it away or choose another output folder"]
    assert sorted(p.name for p in (folder / "out").iterdir()) == ["spectra.csv"]
    assert (folder / "out" / "spectra.csv").read_text() == "the user's own\n"
