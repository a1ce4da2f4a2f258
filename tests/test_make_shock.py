"""``rbhyst make-shock``: records whose SRS, computed here by another method (Smallwood's
ramp-invariant filter through scipy.signal.lfilter, peaks at the samples), lies within
MIL-STD-810's -1.5/+3 dB of three specifications at every 1/12-octave frequency, that end at rest,
keep within the table's limits and come out the same for the same seed."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import invoke
from scipy.signal import lfilter

G = 9.80665
#: a flat one; a knee (a ramp to a plateau, as MIL-STD-810's figures draw them); a shipboard-like one
SPECS = {
    "flat": ([(20.0, 40.0), (2000.0, 40.0)], "displacement=0.05,velocity=2.0,acceleration=60"),
    "knee": ([(10.0, 9.44), (80.0, 75.0), (2000.0, 75.0)], "displacement=0.05,velocity=1.5,acceleration=60"),
    "ship": ([(5.0, 2.0), (20.0, 60.0), (250.0, 60.0), (1000.0, 40.0)], "displacement=0.1,velocity=2.5"),
}


def write_spec(folder, points, unit="g"):
    path = folder / "spec.csv"
    path.write_text(f"frequency_hz,srs_{unit}\n" + "".join(f"{f:g},{a:g}\n" for f, a in points))
    return path


def read_record(path):
    rows = [line.split(",") for line in path.read_text().splitlines()[2:]]
    t, a = np.array(rows, float).T
    return t, a * G


def smallwood_srs(acc, dt, f, q):
    """Maximax absolute acceleration by Smallwood's ramp-invariant recursion (1981), the record
    followed by two periods of the lowest frequency at rest."""
    x = np.concatenate([acc, np.zeros(int(2.0 / (f.min() * dt)))])
    out = []
    for fn in f:
        zeta = 1.0 / (2.0 * q)
        w = 2.0 * math.pi * fn
        wd = w * math.sqrt(1.0 - zeta**2)
        e = math.exp(-zeta * w * dt)
        k = wd * dt
        c, s = e * math.cos(k), e * math.sin(k)
        sp = s / k
        b = [1.0 - sp, 2.0 * (sp - c), e * e - sp]
        a = [1.0, -2.0 * c, e * e]
        out.append(np.abs(lfilter(b, a, x)).max())
    return np.array(out)


def spec_at(points, f):
    fx, ax = np.array(points).T
    return np.exp(np.interp(np.log(f), np.log(fx), np.log(ax))) * G


@pytest.mark.parametrize("name", list(SPECS))
def test_each_record_meets_its_specification_ends_at_rest_and_keeps_to_the_table(tmp_path, name):
    points, table = SPECS[name]
    out = tmp_path / "out"
    code, err = invoke("make-shock", out, "--srs", write_spec(tmp_path, points), "--table", table, "--seed", 3,
                       *(["--no-plots"] if name != "knee" else []))
    assert code == 0, err
    t, acc = read_record(out / "shock_x1.csv")
    dt = t[1] - t[0]
    assert np.allclose(np.diff(t), dt, rtol=1e-6) and t[0] == 0.0
    lo, hi = points[0][0], points[-1][0]
    f = lo * 2.0 ** (np.arange(math.floor(12 * math.log2(hi / lo) + 1e-9) + 1) / 12)
    f = np.append(f, hi) if f[-1] < hi * (1 - 1e-9) else f  # the range's top, where the octaves miss it
    db = 20.0 * np.log10(smallwood_srs(acc, dt, f, 10.0) / spec_at(points, f))
    assert np.all(db >= -1.5) and np.all(db <= 3.0), (f[db < -1.5], f[db > 3.0])
    # at rest at the end: velocity and displacement (trapezoids, twice) below 1 % of their peaks
    v = np.concatenate([[0.0], np.cumsum(0.5 * dt * (acc[1:] + acc[:-1]))])
    d = np.concatenate([[0.0], np.cumsum(0.5 * dt * (v[1:] + v[:-1]))])
    assert abs(v[-1]) < 0.01 * np.abs(v).max() and abs(d[-1]) < 0.01 * np.abs(d).max()
    assert acc[0] == 0.0 and abs(acc[-1]) < 1e-6 * np.abs(acc).max()
    limits = dict(p.split("=") for p in table.split(","))
    assert np.ptp(d) <= float(limits["displacement"]) and np.abs(v).max() <= float(limits["velocity"])
    if "acceleration" in limits:
        assert np.abs(acc).max() / G <= float(limits["acceleration"])
    # srs_check.csv says the same as the record (its own SRS, exact between the samples)
    rows = [line.split(",") for line in (out / "srs_check.csv").read_text().splitlines()[1:]]
    assert np.allclose([float(r[1]) for r in rows], f, rtol=1e-5)
    assert all(r[-1] == "yes" for r in rows)
    assert np.allclose([float(r[4]) for r in rows], db, atol=0.15)  # the samples' peaks against the exact
    assert json.loads((out / "shocks.json").read_text())["records"][0]["within"] is True
    if name == "knee":
        assert (out / "srs_check.png").stat().st_size > 10_000 and (out / "records.png").stat().st_size > 10_000


#: a narrow specification, quick to match
NARROW = [(100.0, 10.0), (400.0, 30.0), (1000.0, 30.0)]


def test_same_seed_same_bytes_damped_sines_and_three_axes(tmp_path):
    spec = write_spec(tmp_path, NARROW)
    runs = {}
    for label, args in {"a": ("--seed", 5), "b": ("--seed", 5), "c": ("--seed", 6)}.items():
        code, err = invoke("make-shock", tmp_path / label, "--srs", spec, "--axes", 3, "--no-plots", *args)
        assert code == 0, err
        runs[label] = [(tmp_path / label / f"shock_{x}.csv").read_bytes() for x in ("x1", "x2", "x3")]
    assert runs["a"] == runs["b"]
    assert runs["a"][0] != runs["c"][0]
    assert len(set(runs["a"])) == 3  # each axis its own record
    out = tmp_path / "ds"
    code, err = invoke("make-shock", out, "--srs", spec, "--method", "damped-sines", "--no-plots")
    assert code == 0, err
    t, acc = read_record(out / "shock_x1.csv")
    f = 100.0 * 2.0 ** (np.arange(12 * 3 + 1) / 12)
    f = np.append(f[f < 1000.0], 1000.0)
    db = 20.0 * np.log10(smallwood_srs(acc, t[1] - t[0], f, 10.0) / spec_at(NARROW, f))
    assert np.all(db >= -1.5) and np.all(db <= 3.0)


@pytest.mark.parametrize("args, code, said", [
    (("--duration", "0.01"), 3, "at least would do"),
    (("--table", "displacement=0.00001"), 3, "would"),
    (("--method", "sines"), 2, "--method: 'sines'"),
    (("--q", "0.2"), 2, "--q: 0.2"),
    (("--table", "speed=1"), 2, "--table: 'speed=1'"),
])
def test_what_cannot_be_done_says_what_would(tmp_path, args, code, said):
    spec = write_spec(tmp_path, NARROW)
    got, err = invoke("make-shock", tmp_path / "o", "--srs", spec, "--no-plots", *args)
    assert got == code, err
    assert said in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_a_specification_no_record_can_meet_says_where_and_what_would_try_again(tmp_path):
    # 40 dB in an octave: at 100 Hz the SRS of the 200 Hz content alone is far above 1 g
    spec = write_spec(tmp_path, [(100.0, 1.0), (200.0, 100.0)])
    code, err = invoke("make-shock", tmp_path / "o", "--srs", spec, "--no-plots")
    assert code == 3 and "worst +" in err and "at 100 Hz" in err and "--method damped-sines" in err, err
    assert not (tmp_path / "o").exists()


def test_a_specification_without_its_unit_names_its_line(tmp_path):
    path = tmp_path / "spec.csv"
    path.write_text("frequency_hz,srs\n10,1\n100,10\n")
    code, err = invoke("make-shock", tmp_path / "o", "--srs", path)
    assert code == 2 and f"{path}:1" in err
