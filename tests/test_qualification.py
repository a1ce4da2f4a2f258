"""Qualification: AC156's and IEEE 693's RRS at their breakpoints, spectrum-compatible motions
read back by ``rbhyst spectrum`` (their peak acceleration held to the standard's least), random
vibration against its PSD, and the verdict against the runs' own summary.json."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from conftest import DECKS, invoke, snapshot, write_deck
from rbhyst.analyses.qualification import matching
from rbhyst.analyses.qualification.psd import load_psd, random_history, tolerance, welch_check
from rbhyst.analyses.qualification.rrs import (ac156, ac156_levels, ieee693, ieee693_beta, read_rrs,
                                               sixth_octave)
from rbhyst.errors import InputError
from rbhyst.model.records import read_record

G = 9.80665


def errors(err: str) -> list[str]:
    """The error lines (a first run may say first that it compiles the kernels)."""
    return [line for line in err.splitlines() if not line.startswith("note: compiling")]


# ---------------------------------------------------------------- the RRS


@pytest.mark.parametrize("sds, zh, levels", [
    (1.0, 1.0, (1.6, 1.2, 0.67, 0.27)),   # the roof: both horizontal levels at their caps
    (1.0, 0.5, (1.6, 0.8, 0.67, 0.27)),   # A_FLX-H = 2 S_DS capped at 1.6 S_DS
    (1.0, 0.0, (1.0, 0.4, 0.67, 0.27)),   # at grade
    (1.5, 0.25, (2.25, 0.9, 1.005, 0.405)),
])
def test_ac156_levels_are_the_standards(sds, zh, levels):
    got = ac156_levels(sds, zh)
    assert [got[k] for k in ("AFLX-H", "ARIG-H", "AFLX-V", "ARIG-V")] == pytest.approx(levels, rel=1e-12)


@pytest.mark.parametrize("axis, flx, rig", [("x1", 1.6, 1.2), ("x2", 0.67, 0.27)])
def test_ac156_shape_at_its_breakpoints(axis, flx, rig):
    r = ac156(1.0, 1.0)[axis]
    sa = lambda f: float(r(f)) / G  # noqa: E731
    assert r.damping == 0.05 and r.check_range == (1.3, 33.3) and r.band == (0.9, 1.3)
    for f, want in ((1.3, flx), (3.0, flx), (8.3, flx), (33.3, rig), (50.0, rig), (100.0, rig)):
        assert sa(f) == pytest.approx(want, rel=1e-12)
    # straight on log-log axes from A_FLX at 8.3 Hz to A_RIG at 33.3 Hz: the geometric means meet
    assert sa(math.sqrt(8.3 * 33.3)) == pytest.approx(math.sqrt(flx * rig), rel=1e-12)
    # below 1.3 Hz the figure's line through A_FLX / 10 at 0.1 Hz: A_FLX (f / 1.3)^(ln 10 / ln 13)
    for f in (0.1, 0.5, 1.0):
        assert sa(f) == pytest.approx(flx * (f / 1.3) ** (math.log(10) / math.log(13)), rel=1e-12)


def test_ieee693_beta_is_one_at_5_percent():
    # Newmark and Hall's median amplification 3.21 - 0.68 ln(zeta %) over its value at 5 %
    assert ieee693_beta(0.05) == (3.21 - 0.68 * math.log(5)) / 2.1156 == pytest.approx(1.0, abs=1e-5)
    assert ieee693_beta(0.02) == pytest.approx(1.2945074, rel=1e-7)
    assert ieee693_beta(0.10) == pytest.approx(0.7771990, rel=1e-6)


@pytest.mark.parametrize("damping, beta", [(0.05, 0.99999160), (0.02, 1.29450743)])
def test_ieee693_high_level_at_its_breakpoints(damping, beta):
    r = ieee693("high", damping)
    sa = lambda f: float(r["x1"](f)) / G  # noqa: E731
    assert r["x1"].damping == damping and r["x1"].check_range == (1.1, 33.0) and r["x1"].band == (1.0, 1.3)
    assert ieee693_beta(damping) == pytest.approx(beta, rel=1e-7)
    beta = ieee693_beta(damping)
    # below the lower corner 2.288 beta f; the plateau 2.5 beta from 1.1 to 8 Hz; the ZPA 1 g from 33 Hz
    for f in (0.3, 0.5, 1.0, 1.09):
        assert sa(f) == pytest.approx(2.288 * beta * f, rel=1e-7)
    for f in (1.1, 3.0, 8.0):
        assert sa(f) == pytest.approx(2.5 * beta, rel=1e-7)
    for f in (33.0, 50.0, 100.0):
        assert sa(f) == pytest.approx(1.0, rel=1e-15)
    for f in (8.5, 15.0, 25.0):
        assert sa(f) == pytest.approx((26.4 * beta - 10.56) / f - 0.8 * beta + 1.32, rel=1e-12)
    # continuous at 8 Hz and 33 Hz whatever beta; at 1.1 Hz the formulas step by 0.7 % (2.288 x 1.1 = 2.5168)
    assert sa(8.0 * (1 + 1e-9)) == pytest.approx(sa(8.0), rel=1e-8)
    assert sa(33.0 * (1 - 1e-9)) == pytest.approx(1.0, rel=1e-8)
    assert sa(1.1 * (1 - 1e-12)) / sa(1.1) == pytest.approx(2.288 * 1.1 / 2.5, rel=1e-9)


def test_ieee693_moderate_is_half_the_high_and_the_vertical_80_percent():
    f = np.geomspace(0.2, 80.0, 60)
    for damping in (0.02, 0.05, 0.1):
        high, moderate = ieee693("high", damping), ieee693("moderate", damping)
        assert np.allclose(moderate["x1"](f), 0.5 * high["x1"](f), rtol=1e-15, atol=0)
        for r in (high, moderate):
            assert np.allclose(r["x2"](f), 0.8 * r["x1"](f), rtol=1e-15, atol=0)
    # the moderate level at 5 %: 1.25 g plateau, 0.5 g ZPA; the high level at 5 %: 2.5 g, 1 g
    assert float(ieee693("moderate")["x1"](4.0)) / G == pytest.approx(1.25, rel=1e-5)
    assert float(ieee693("moderate")["x1"](40.0)) / G == pytest.approx(0.5, rel=1e-15)
    assert [ieee693(level)[axis].peak_min / G for level in ("high", "moderate") for axis in ("x1", "x2")] == \
        pytest.approx([1.0, 0.8, 0.5, 0.4], rel=1e-15)


def test_ieee693_and_ac156_peak_checks_in_the_describe():
    d = ieee693("high")["x2"].describe()
    assert d["peak_min_ratio"] == 1.0 and d["peak_min_g"] == pytest.approx(0.8) and "Figure A.1" in d["source"]
    d = ac156(1.0, 0.5)["x1"].describe()
    assert d["peak_min_ratio"] == 0.9 and d["peak_min_g"] == pytest.approx(0.72)
    assert read_rrs_describe_has_no_peak()


@pytest.mark.parametrize("level, damping", [("high", 0.05), ("moderate", 0.02)])
def test_ieee693_as_written_is_the_curve_checked(level, damping):
    """qualification.json's and motions.json's RRS, read log-log between its points as a reader
    of the file would, is the formula the TRS is held to (its breakpoints alone gave 1.60 g at
    16 Hz for the checked 1.51 g)."""
    for axis, r in ieee693(level, damping).items():
        d = json.loads(json.dumps(r.describe()))
        f = np.geomspace(0.1, 100.0, 4001)
        read = np.exp(np.interp(np.log(f), np.log(d["frequency_hz"]), np.log(d["sa_g"])))
        assert np.allclose(read, r(f) / G, rtol=2e-5, atol=0)
        assert d["breakpoints_hz"] == [0.1, 1.1, 8.0, 33.0, 100.0] and "2.288 beta f" in d["formula"]


def read_rrs_describe_has_no_peak() -> bool:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rrs.csv"
        path.write_text("frequency_hz,sa_g\n1.0,0.5\n10.0,1.0\n")
        d = read_rrs(path, 0.05).describe()
    return d["peak_min_ratio"] is None and d["peak_min_g"] is None


def test_a_record_short_of_its_least_peak_fails_the_check():
    rrs = ac156(1.0, 0.5)["x1"]
    f = sixth_octave(*rrs.check_range)
    within = matching.Check(f, rrs(f), 1.1 * rrs(f), rrs.band, 0.89 * 0.8 * G, rrs.peak_min)
    assert within.within.all() and not within.peak_ok and not within.ok
    s = within.summary()
    assert s["within_band"] and not s["peak_pass"] and not s["pass"] and s["peak_min_g"] == pytest.approx(0.72)
    assert within.said_peak() == "its peak acceleration 0.712 g is below 0.72 g (0.9 times the RRS at 33.3 Hz)"
    assert matching.Check(f, rrs(f), 1.1 * rrs(f), rrs.band, 0.91 * 0.8 * G, rrs.peak_min).ok


def test_sixth_octave_points_cover_the_range():
    f = sixth_octave(1.3, 33.3)
    assert f[0] == 1.3 and f[-1] == 33.3 and len(f) == 30
    assert np.allclose(np.diff(np.log2(f[:-1])), 1 / 6)


def test_rrs_files_state_their_units(tmp_path):
    good = tmp_path / "rrs.csv"
    good.write_text("frequency_hz,sa_m_s2\n1.0,5.0\n10.0,10.0\n40.0,4.0\n")
    r = read_rrs(good, 0.02)
    assert r.check_range == (1.0, 40.0) and r.damping == 0.02 and float(r(10.0)) == pytest.approx(10.0, rel=1e-15)
    bare = tmp_path / "bare.csv"
    bare.write_text("f,sa\n1.0,0.5\n10.0,1.0\n")
    with pytest.raises(InputError) as err:
        read_rrs(bare, 0.05)
    assert err.value.problems == [f"{bare}:1: the header must state the value's unit, as record files do: "
                                  "frequency_hz,sa_g (or sa_m_s2, sa [g], ...)"]
    down = tmp_path / "down.csv"
    down.write_text("frequency_hz,sa_g\n1.0,0.5\n10.0,1.0\n5.0,1.0\n")
    with pytest.raises(InputError) as err:
        read_rrs(down, None)
    assert err.value.problems == [f"{down}:4: the frequency 5 Hz does not increase (previous 10 Hz)"]


# ---------------------------------------------------------------- make-motion


AC156_OPTIONS = ("--rrs", "ac156", "--sds", "1.0", "--z-over-h", "0.5", "--duration", "30", "--seed", "3")


@pytest.fixture(scope="module")
def motion(tmp_path_factory):
    out = tmp_path_factory.mktemp("motion") / "ac156"
    code, err = invoke("make-motion", out, *AC156_OPTIONS)
    assert code == 0, err
    return out


def _acc_g(path: Path) -> tuple[float, np.ndarray]:
    s = read_record(path).series
    return s.dt, s.values


def test_the_trs_read_back_by_rbhyst_spectrum_lies_within_the_band(motion, tmp_path):
    rrs = ac156(1.0, 0.5)
    f = sixth_octave(1.3, 33.3)
    trs_csv = np.genfromtxt(motion / "trs.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    for axis in ("x1", "x2"):
        code, err = invoke("spectrum", motion / f"m1_{axis}.csv", "--units", "g", "--damping", "0.05",
                           "--periods", ",".join(repr(float(1 / x)) for x in f), "--out", tmp_path / axis, "--no-plots")
        assert code == 0, err
        rows = np.genfromtxt(tmp_path / axis / "spectra.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
        order = np.argsort(rows["frequency_hz"])
        assert np.allclose(rows["frequency_hz"][order], f, rtol=1e-9)
        sa = rows["sa_m_s2"][order]
        ratio = sa / rrs[axis](f)
        assert np.all(ratio >= 0.9) and np.all(ratio <= 1.3), ratio
        mine = trs_csv[trs_csv["axis"] == axis]
        assert np.allclose(mine["frequency_hz"], f, rtol=1e-5)
        assert np.allclose(mine["trs_g"] * G, sa, rtol=1e-5)  # trs.csv is what rbhyst spectrum reads
        assert set(mine["within"]) == {"yes"}


def test_motions_end_at_rest_are_independent_and_strong_for_20_s(motion):
    dt, x1 = _acc_g(motion / "m1_x1.csv")
    _, x2 = _acc_g(motion / "m1_x2.csv")
    assert dt == 0.005 and len(x1) == 6001 and x1[0] == 0.0 and x1[-1] == 0.0
    for a in (x1, x2):
        v, d = matching.integrate(a * G, dt)  # exact for a record linear between its samples
        # to the rounding of the file's 10 digits (6e-8 of the peak displacement at most, on 60 motions)
        assert abs(v[-1]) < 1e-6 * np.abs(v).max() and abs(d[-1]) < 1e-6 * np.abs(d).max()
    assert abs(np.corrcoef(x1, x2)[0, 1]) < 0.3
    facts = json.loads((motion / "motions.json").read_text())["motions"][0]
    assert abs(facts["correlation_x1_x2"]) < 0.3
    assert all(a["trs"]["pass"] for a in facts["axes"].values())
    # the strong motion measured, as the standards define it, equal to an independent measure
    from independent_spectra import arias_duration, bracketed_duration

    rows = np.genfromtxt(motion / "records.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    for axis, a in (("x1", x1), ("x2", x2)):
        mine, row = facts["axes"][axis], rows[rows["axis"] == axis][0]
        assert mine["bracketed_25_s"] == pytest.approx(bracketed_duration(a, dt), abs=0.05)
        assert mine["arias_5_75_s"] == pytest.approx(arias_duration(a, dt, 0.05, 0.75), abs=0.05)
        assert mine["arias_5_95_s"] == pytest.approx(arias_duration(a, dt, 0.05, 0.95), abs=0.05)
        assert mine["strong_motion_s"] == mine["bracketed_25_s"] >= 20.0 and mine["strong_motion_pass"]
        assert mine["arias_5_75_s"] < mine["arias_5_95_s"] < mine["bracketed_25_s"] < 30.0
        assert row["strong_motion_s"] == pytest.approx(mine["strong_motion_s"], abs=1e-4)
        assert row["strong_motion_min_s"] == 20.0 and row["strong_motion_within"] == "yes"
        v, d = matching.integrate(a * G, dt)
        assert row["pgd_m"] == pytest.approx(np.abs(d).max(), rel=1e-5)
        assert row["pgv_m_s"] == pytest.approx(np.abs(v).max(), rel=1e-5)
        assert row["displacement_peak_to_peak_m"] == pytest.approx(np.ptp(d), rel=1e-5)
    assert facts["duration_s"] == 30.0 and facts["strong_motion_s"] == min(
        facts["axes"][a]["strong_motion_s"] for a in ("x1", "x2"))


def test_the_ac156_motion_peaks_at_least_at_90_percent_of_a_rig(motion):
    rrs = ac156(1.0, 0.5)
    facts = json.loads((motion / "motions.json").read_text())["motions"][0]["axes"]
    rows = np.genfromtxt(motion / "trs.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    for axis in ("x1", "x2"):
        _, a = _acc_g(motion / f"m1_{axis}.csv")
        least = 0.9 * float(rrs[axis](33.3)) / G
        assert np.abs(a).max() >= least
        t = facts[axis]["trs"]
        assert t["peak_g"] == np.abs(a).max() and t["peak_min_g"] == pytest.approx(least) and t["peak_pass"]
        assert 0.0 < facts[axis]["strong_part_ratio"] < 1.0
        mine = rows[rows["axis"] == axis]
        assert np.allclose(mine["peak_g"], np.abs(a).max(), rtol=1e-5) and set(mine["peak_within"]) == {"yes"}
        assert np.allclose(mine["peak_min_g"], least, rtol=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("spectra, seed", [
    (lambda: ac156(1.0, 0.0), 1),  # the vertical dipped to 0.88 x RRS at 1.8 Hz between 1/6-octave points
    (lambda: ac156(2.5, 1.0), 2),
    (lambda: ac156(0.5, 0.5), 3),
    (lambda: ieee693("high"), 1),
    (lambda: ieee693("moderate"), 2),
    (lambda: ieee693("high", 0.02), 3),
    (lambda: ieee693("moderate", 0.02), 1),
])
def test_made_motions_lie_in_the_band_on_a_fine_grid_by_an_independent_spectrum(spectra, seed):
    from independent_spectra import octave_grid, trs

    rrs = spectra()
    m, = matching.make_motions(rrs, 1, 30.0, 0.005, seed)
    for axis, r in rrs.items():
        f = octave_grid(*r.check_range, 48)
        ratio = trs(m.records[axis].acc_g * G, 0.005, f, r.damping) / r(f)
        lo, hi = r.band
        assert ratio.min() >= lo and ratio.max() <= hi, (axis, ratio.min(), f[ratio.argmin()], ratio.max())
        c = m.records[axis].check.summary()  # the least and largest anywhere, as computed here
        assert c["fine_frequencies"] == len(f) and c["min_ratio"] == pytest.approx(ratio.min(), rel=4e-3)
        assert c["max_ratio"] == pytest.approx(ratio.max(), rel=4e-3)


def test_the_fine_grid_holds_the_standards_points_and_trs_fine_csv_is_its_table(motion):
    coarse = np.genfromtxt(motion / "trs.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    fine = np.genfromtxt(motion / "trs_fine.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert coarse.dtype.names == fine.dtype.names
    for axis in ("x1", "x2"):
        c, f = coarse[coarse["axis"] == axis], fine[fine["axis"] == axis]
        assert len(c) == 30 and len(f) == 226  # 1.3-33.3 Hz at 1/6 and 1/48 octave
        per_decade = (len(f) - 1) / np.log10(f["frequency_hz"][-1] / f["frequency_hz"][0])
        assert per_decade >= 100  # NRC SRP 3.7.1
        k = np.searchsorted(f["frequency_hz"], c["frequency_hz"] * (1 - 1e-6))
        assert np.allclose(f["frequency_hz"][k], c["frequency_hz"], rtol=1e-5)
        assert np.array_equal(f["trs_g"][k], c["trs_g"])
        facts = json.loads((motion / "motions.json").read_text())["motions"][0]["axes"][axis]["trs"]
        assert facts["min_ratio"] == pytest.approx(f["ratio"].min(), rel=1e-5)
        assert facts["min_at_hz"] == pytest.approx(f["frequency_hz"][f["ratio"].argmin()], rel=1e-5)


def test_a_dip_between_the_standards_points_fails_the_check():
    rrs = ac156(1.0, 0.0)["x1"]
    f = matching.fine_grid(*rrs.check_range)
    points = matching.standard_points(f, rrs.check_range)
    sa = 1.1 * rrs(f)
    sa[np.flatnonzero(~points)[40]] = 0.85 * rrs(f[np.flatnonzero(~points)[40]])  # off every 1/6-octave point
    c = matching.Check(f[points], rrs(f[points]), sa[points], rrs.band, 1.0, None, f, rrs(f), sa)
    assert c.within.all() and not c.fine_within.all() and not c.ok
    s = c.summary()
    assert s["min_ratio"] == pytest.approx(0.85) and s["outside_hz"] == []
    assert s["outside_fine_hz"] == [[f[~points][40], f[~points][40]]]


def test_three_axes_for_a_triaxial_table(tmp_path):
    from independent_spectra import octave_grid, trs

    out = tmp_path / "m3"
    code, err = invoke("make-motion", out, "--rrs", "ac156", "--sds", "1.0", "--z-over-h", "0.5", "--axes", "3",
                       "--seed", "2", "--no-plots")
    assert code == 0, err
    rrs = {"x1": ac156(1.0, 0.5)["x1"], "x2": ac156(1.0, 0.5)["x1"], "x3": ac156(1.0, 0.5)["x2"]}
    acc = {axis: _acc_g(out / f"m1_{axis}.csv") for axis in ("x1", "x2", "x3")}
    for axis, (dt, a) in acc.items():
        f = octave_grid(1.3, 33.3)
        ratio = trs(a * G, dt, f, 0.05) / rrs[axis](f)
        assert 0.9 <= ratio.min() and ratio.max() <= 1.3, axis
    for a, b in (("x1", "x2"), ("x1", "x3"), ("x2", "x3")):
        assert abs(np.corrcoef(acc[a][1], acc[b][1])[0, 1]) < 0.3
    m = json.loads((out / "motions.json").read_text())["motions"][0]
    assert set(m["correlations"]) == set(m["coherence"]) == {"x1_x2", "x1_x3", "x2_x3"}
    assert all(0.0 <= c["mean"] < 0.15 and c["band_hz"] == [1.3, 33.3] for c in m["coherence"].values())
    assert m["files"] == {axis: f"m1_{axis}.csv" for axis in ("x1", "x2", "x3")}
    assert (out / "m1_x3.csv").read_text().splitlines()[0].endswith("motion 1, x3 (vertical)")
    assert any(line.startswith("motion 1: correlation of x2 and x3 ") for line in err.splitlines())
    code, err = invoke("make-motion", tmp_path / "no", "--rrs", "a.csv", "--rrs-x3", "b.csv", "--rrs-damping", "0.05")
    assert code == 2 and errors(err) == [
        "error: --rrs-x3: only with --axes 3 (with two axes the vertical is x2: --rrs-x2)"]
    code, err = invoke("make-motion", tmp_path / "no", "--rrs", "ac156", "--sds", "1", "--z-over-h", "0", "--axes", "4")
    assert code == 2 and errors(err) == [
        "error: --axes: 4: 2 (x1 horizontal, x2 vertical) or 3 (x1, x2 horizontal, x3 vertical)"]
    assert not (tmp_path / "no").exists()


def test_the_same_seed_gives_the_same_bits(motion, tmp_path):
    code, err = invoke("make-motion", tmp_path / "again", *AC156_OPTIONS, "--no-plots")
    assert code == 0, err
    for name in ("m1_x1.csv", "m1_x2.csv", "trs.csv"):
        assert (tmp_path / "again" / name).read_bytes() == (motion / name).read_bytes()
    assert (motion / "trs.png").stat().st_size > 10_000


def test_a_motion_that_cannot_be_matched_is_exit_3_with_what_would_work(tmp_path, monkeypatch):
    monkeypatch.setattr(matching, "MAX_ITERATIONS", 0)
    out = tmp_path / "none"
    code, err = invoke("make-motion", out, *AC156_OPTIONS)
    assert code == 3 and not out.exists()
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: motion 1 (seed 3) cannot be matched after 0 iterations: ")
    assert "a longer --duration (45 s) or a finer --dt (0.0025 s) may" in lines[0]


def test_make_motion_mistakes_are_one_line_each(tmp_path):
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", "ac156", "--sds", "-1", "--z-over-h", "1.5",
                       "--duration", "20")
    assert code == 2
    assert err.splitlines() == ["error: --sds: -1 must be a positive number of g",
                                "error: --z-over-h: 1.5 must be from 0 (grade) to 1 (roof): z is at most h"]
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", "ac156", "--sds", "1", "--z-over-h", "0.5",
                       "--duration", "20")
    assert code == 2 and err.splitlines() == [
        "error: --duration: 20 s: AC156 asks for 20 s of strong motion within at least 30 s (ramps of 5 s): "
        "--duration 30 or more"]
    rrs = tmp_path / "rrs.csv"
    rrs.write_text("frequency_hz,sa_g\n2,0.5\n20,1.0\n")
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", rrs, "--sds", "1")
    assert code == 2 and err.splitlines() == [
        "error: --sds: only with --rrs ac156",
        "error: --rrs-damping: required with an RRS file: the damping ratio it is drawn for (0.05 for 5 %)"]
    assert not (tmp_path / "m").exists()


def test_an_ieee693_motion_envelops_its_rrs_and_peaks_at_its_zpa(tmp_path):
    out = tmp_path / "ieee"
    code, err = invoke("make-motion", out, "--rrs", "ieee693", "--level", "moderate", "--duration", "30",
                       "--seed", "5", "--no-plots")
    assert code == 0, err
    rrs = ieee693("moderate")
    f = sixth_octave(1.1, 33.0)
    summary = json.loads((out / "motions.json").read_text())
    assert summary["standard"] == "ieee693" and summary["rrs"]["x2"]["peak_min_g"] == pytest.approx(0.4)
    for axis in ("x1", "x2"):
        dt, a = _acc_g(out / f"m1_{axis}.csv")
        check = matching.check_record(a * G, dt, rrs[axis])  # the file's digits, checked again
        assert np.allclose(check.frequency_hz, f) and check.frequency_hz[0] == 1.1
        assert np.all(check.ratio >= 1.0) and np.all(check.ratio <= 1.3), check.ratio
        assert np.abs(a).max() >= float(rrs[axis](33.0)) / G  # the ZPA: 0.5 g, 0.4 g
    assert summary["motions"][0]["strong_motion_s"] >= 20.0  # IEEE 693's 20 s, measured
    code, err = invoke("make-motion", tmp_path / "short", "--rrs", "ieee693", "--level", "high", "--duration", "25")
    assert code == 2 and err.splitlines() == [
        "error: --duration: 25 s: IEEE 693 asks for 20 s of strong motion (ramps of 5 s): --duration 30 or more"]
    code, err = invoke("make-motion", tmp_path / "bad", "--rrs", "ieee693", "--level", "low", "--rrs-damping", "0.3",
                       "--z-over-h", "0.5")
    assert code == 2 and err.splitlines() == [
        "error: --level: 'low': high or moderate",
        "error: --rrs-damping: 0.3: IEEE 693's damping factor is used from 0.005 to 0.2 (0.05 by default, the "
        "damping it is matched at)",
        "error: --z-over-h: only with --rrs ac156"]
    assert not (tmp_path / "short").exists() and not (tmp_path / "bad").exists()


def test_a_user_rrs_is_matched_on_its_own_range(tmp_path):
    rrs = tmp_path / "rrs.csv"
    rrs.write_text("frequency_hz,sa [g]\n2.0,0.4\n5.0,1.0\n15.0,1.0\n30.0,0.5\n")
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", rrs, "--rrs-damping", "0.02", "--duration", "20",
                       "--seed", "5", "--no-plots")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == [".rbhyst.json", "m1_x1.csv", "motions.json",
                                                                  "records.csv", "trs.csv", "trs_fine.csv"]
    r = read_rrs(rrs, 0.02)
    dt, a = _acc_g(tmp_path / "m" / "m1_x1.csv")
    check = matching.check_record(a * G, dt, r)
    assert check.ok and check.frequency_hz[0] == 2.0 and check.frequency_hz[-1] == 30.0


# ---------------------------------------------------------------- random vibration

#: a MIL-STD-810-style table: +6 dB/octave, a plateau, -6 dB/octave (g2/Hz)
TABLE = [[10.0, 0.0025], [40.0, 0.04], [200.0, 0.04], [500.0, 0.0064]]


def test_random_vibration_meets_its_psd_band_by_band_and_its_rms():
    psd = load_psd(TABLE, "g2/Hz", Path("."))
    dt, x = random_history(psd, 30.0, seed=11)
    assert dt == pytest.approx(1 / 5000)
    full = x[int(2.0 / dt) + 1:-int(2.0 / dt) - 1]  # between its 2 s ramps
    bands, rms, target = welch_check(full, dt, psd)
    assert [(b.f_lo, b.f_hi) for b in bands] == [(10.0, 40.0), (40.0, 200.0), (200.0, 500.0)]
    assert all(b.bins >= 8 and abs(b.db) <= 3.0 for b in bands), [(b.bins, b.db) for b in bands]
    # the exact integral of the table: 0.0025 * 10 / 3 (4^3 - 1) + 0.04 * 160 + 0.04 * 200 (1 - 0.4)
    assert target / G == pytest.approx(math.sqrt(0.0025 * 10 / 3 * 63 + 6.4 + 8.0 * 0.6), rel=1e-12)
    assert abs(rms / target - 1.0) < 0.02
    # Gaussian and stationary at full level: kurtosis 3, and the same rms in each third
    z = (full - full.mean()) / full.std()
    assert abs(np.mean(z**4) - 3.0) < 0.1 and abs(np.mean(z**3)) < 0.05
    thirds = [np.sqrt(np.mean(p**2)) / rms for p in np.array_split(full, 3)]
    assert np.allclose(thirds, 1.0, atol=0.03)
    # MIL-STD-810H's tolerances, checked independently here: every Welch line within 3 dB
    from scipy.signal import welch

    f, pxx = welch(full, fs=1 / dt, window="hann", nperseg=2048, noverlap=1024, detrend=False)
    inside = (f > 10.0 + f[1]) & (f < 500.0 - f[1])
    assert np.all(np.abs(10 * np.log10(pxx[inside] / psd(f[inside]))) <= 3.0)
    check = tolerance(x, dt, psd, 2.0)
    assert check["pass"] and check["lines_outside"] == 0 and check["rms_m_s2"] == pytest.approx(rms, rel=1e-4)


def test_random_vibration_starts_and_ends_at_rest_and_its_drive_stays_bounded():
    """As a controller drives a shaker: no step at the start (4.09 g before), no drift of the
    ground (1.45 m in 30 s before), the drive displacement a few times its rms."""
    psd = load_psd(TABLE, "g2/Hz", Path("."))
    dt, x = random_history(psd, 30.0, seed=11)
    v, d = matching.integrate(x, dt)
    assert x[0] == 0.0 and abs(x[-1]) < 1e-12 * np.abs(x).max()
    assert abs(v[-1]) < 1e-9 * np.abs(v).max() and abs(d[-1]) < 1e-9 * np.abs(d).max()
    assert np.max(np.abs(x[: int(0.01 / dt)])) < 0.01 * np.abs(x).max()  # a ramp, not a step
    # the displacement's rms from the PSD: the integral of PSD / (2 pi f)^4
    f = np.geomspace(10.0, 500.0, 20001)
    d_rms = math.sqrt(np.trapezoid(psd(f) / (2 * np.pi * f) ** 4, f))
    assert np.abs(d).max() < 6.0 * d_rms and np.ptp(d) < 10.0 * d_rms
    # sigma clipping: every peak within 3 rms, the PSD still within its tolerances
    dt, y = random_history(psd, 30.0, seed=11, clip_sigma=3.0)
    assert np.abs(y).max() <= 3.0 * psd.rms * (1 + 1e-6) < np.abs(x).max()
    assert tolerance(y, dt, psd, 2.0)["pass"]


def test_random_vibration_out_of_its_tolerance_warns_and_too_short_to_check_says_so():
    from types import SimpleNamespace

    from rbhyst.model.plausible import random_warnings
    from rbhyst.model.system import RandomSeries

    psd = load_psd(TABLE, "g2/Hz", Path("."))
    dt, x = random_history(psd, 30.0, seed=11)
    loud = tolerance(1.2 * x, dt, psd, 2.0)  # +1.6 dB: every line in, the rms 20 % over
    assert loud["pass"] is False and loud["lines_outside"] == 0 and not loud["rms_pass"]
    ex = SimpleNamespace(ag1=RandomSeries(0.0, dt, x, loud), ag2=RandomSeries(0.0, dt, x, tolerance(x, dt, psd, 2.0)))
    line, = random_warnings(ex)
    assert line.startswith("excitation.support.x1: random vibration NOT within the tolerances of MIL-STD-810H")
    dt, short = random_history(psd, 3.0, seed=11)
    check = tolerance(short, dt, psd, 0.3)
    assert check["pass"] is None and check["dof"] < 120 and "at least" in check["why"]
    assert random_warnings(SimpleNamespace(ag1=RandomSeries(0.0, dt, short, check))) == []


def test_random_vibration_is_the_same_bits_for_the_same_seed():
    psd = load_psd(TABLE, "g2/Hz", Path("."))
    a = random_history(psd, 5.0, seed=4)[1]
    assert a.tobytes() == random_history(psd, 5.0, seed=4)[1].tobytes()
    assert a.tobytes() != random_history(psd, 5.0, seed=5)[1].tobytes()


def _random_deck(tmp_path, support: dict, **analysis) -> Path:
    cab = tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())
    cab["excitation"] = {"support": support}
    cab["analysis"] = {"dt": 0.001, **analysis}
    cab["output"] = {"plots": False}
    return write_deck(tmp_path, cab)


def test_random_vibration_drives_every_integrator(tmp_path):
    import rbhyst

    psd = [[5.0, 0.001], [20.0, 0.004], [60.0, 0.004], [100.0, 0.001]]
    deck = rbhyst.load_deck(_random_deck(tmp_path, {
        "x1": {"type": "random", "psd": psd, "units": "g2/Hz", "duration": 4.0, "seed": 2},
        "x2": {"type": "random", "psd": psd, "units": "g2/Hz", "duration": 4.0, "seed": 3, "scale": 0.5}}))
    chang = rbhyst.run(deck, estimate=False)
    adaptive = rbhyst.run(deck, integrator="adaptive", estimate=False)
    dt, x = random_history(load_psd(psd, "g2/Hz", Path(".")), 4.0, seed=2)
    # the run's support acceleration is the history, linear between its samples, zero after it
    assert np.allclose(chang.column("ag1_m_s2"), np.interp(chang.time, dt * np.arange(len(x)), x, right=0.0),
                       rtol=0, atol=1e-12 * np.abs(x).max())
    for col in ("u1_m", "u2_m", "at1_m_s2"):
        assert chang.extremes.peak(col) == pytest.approx(adaptive.extremes.peak(col), rel=0.02)


def test_random_vibration_mistakes_name_their_place(tmp_path):
    psd_file = tmp_path / "psd.csv"
    psd_file.write_text("frequency_hz,psd [(m/s2)2/Hz]\n20,0.1\n80,0.4\n")
    deck = _random_deck(tmp_path, {
        "x1": {"type": "random", "psd": [[20.0, 0.01], [10.0, 0.04]], "units": "g2/Hz", "duration": 4.0, "seed": 2},
        "x2": {"type": "random", "psd": "psd.csv", "units": "g2/Hz", "duration": 4.0, "seed": 2}})
    code, err = invoke("run", deck, "--out", tmp_path / "out")
    assert code == 2 and errors(err) == [
        "error: excitation.support.x1.psd[2]: the frequency 10 Hz does not increase (the breakpoint before is at 20 Hz)"]
    deck = _random_deck(tmp_path, {
        "x1": {"type": "random", "psd": [[20.0, 0.01], [80.0, 0.04]], "units": "g2/Hz", "duration": 4.0, "seed": 2,
               "dt": 0.01},
        "x2": {"type": "random", "psd": "psd.csv", "units": "g2/Hz", "duration": 4.0, "seed": 2}})
    code, err = invoke("run", deck, "--out", tmp_path / "out")
    assert code == 2 and errors(err) == [
        "error: excitation.support.x1: dt: 0.01 s samples at 100 Hz, too coarse for the PSD's 80 Hz: at most "
        "0.005 s (2.5 samples a period), 0.00125 s by default",
        f"error: excitation.support.x2: {psd_file}:1: the header declares 'psd [(m/s2)2/Hz]' ((m/s2)2/Hz) but the deck "
        'says units = "g2/Hz"']
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------- the verdict


def _cabinet(tmp_path, qualify: dict | None = None, **changes) -> Path:
    """The sample cabinet with strokes on its isolators, a point at its top and a [qualify]."""
    cab = tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())
    for el in cab["elements"]:
        el["stroke"] = 0.05
    for sig in cab["excitation"]["support"].values():
        sig["file"] = str(DECKS / sig["file"])
    cab["output"] = {"points": [{"name": "top", "point": [0.0, 2.0]}]}
    cab["qualify"] = qualify if qualify is not None else {
        "standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "seed": 2,
        "acceleration_limit_g": {"top": 3.0, "G": [2.0, 1.5]}, "force_capacity_N": {"e1": 20000.0, "e5": 20000.0}}
    for key, value in changes.items():
        cab[key] = value
    return write_deck(tmp_path, cab)


def test_the_verdict_takes_its_demands_from_the_runs_summary(tmp_path):
    import rbhyst

    deck = DECKS / "cabinet_qualify.toml"  # the sample: strokes, a point at the top, [qualify]
    out = tmp_path / "q"
    code, err = invoke("qualify", deck, "--out", out, "--motions", "2", "--seed", "4")
    assert code == 0, err
    assert err.splitlines()[-2].startswith("verdict: pass: 16 criteria, 16 within capacity; least margin ")
    q = json.loads((out / "qualification.json").read_text())
    assert q["pass"] and q["trs"]["pass"] and q["accuracy"]["pass"] and q["warnings"] == []
    assert q["statistic"] == {"asked": "max", "used": "max", "motions": 2,
                              "rule": "the largest over the 2 motions: each motion a test the equipment must pass"}
    summaries = [json.loads((out / f"run_{k}" / "summary.json").read_text()) for k in (1, 2)]
    kinds = [c["criterion"] for c in q["criteria"]]
    assert kinds == ["stroke"] * 4 + ["acceleration"] * 4 + ["force"] * 8
    for c in q["criteria"]:
        if c["criterion"] == "stroke":
            i = int(c["item"].split("[")[1].split("]")[0]) - 1
            per = [abs(s["elements"][i]["stroke"]["peak_deformation_m"]) for s in summaries]
        elif c["criterion"] == "acceleration":
            per = [s["peaks"][c["column"]] / G for s in summaries]
        else:
            per = [s["peaks"][c["column"]] for s in summaries]
        assert c["per_motion"] == per and c["demand"] == max(per)
        assert c["margin"] == 1 - c["demand"] / c["capacity"] and c["pass"] == (c["demand"] <= c["capacity"])
    # the same motions through rbhyst.run give the same figures, to the bit
    cab = rbhyst.load_deck(deck)
    for k, s in enumerate(summaries, start=1):
        support = {axis: {"file": str(out / "motions" / f"m{k}_{axis}.csv"), "units": "g"} for axis in ("x1", "x2")}
        again = rbhyst.run(cab.with_values({"excitation.support": support})).summary()
        assert again["peaks"] == s["peaks"] and again["elements"] == s["elements"]
    assert {p.name for p in out.iterdir()} == {".rbhyst.json", "motions", "run_1", "run_2", "trs.csv", "trs_fine.csv",
                                                    "records.csv", "motions.json",
                                                "qualification.json", "qualification.png"}


def test_every_motion_is_judged_and_the_mean_is_the_demand_only_where_asked(tmp_path):
    (tmp_path / "rrs.csv").write_text("frequency_hz,sa_g\n2.0,1.0\n20.0,1.0\n")
    qualify = {"rrs": "rrs.csv", "rrs_damping": 0.05, "motions": 7, "duration": 8.0, "seed": 3}
    first = _cabinet(tmp_path, {**qualify, "acceleration_limit_g": {"top": 50.0}})
    code, err = invoke("qualify", first, "--out", tmp_path / "q0", "--no-plots")
    assert code == 0, err
    q = json.loads((tmp_path / "q0" / "qualification.json").read_text())
    per = [s["peaks"]["top_at1_m_s2"] / G for s in
           (json.loads((tmp_path / "q0" / f"run_{k}" / "summary.json").read_text()) for k in range(1, 8))]
    assert q["statistic"]["used"] == "max" and q["criteria"][-2]["per_motion"] == per  # top x1
    # a capacity the mean of the seven is within and some of them are not
    cap = 0.5 * (np.mean(per) + max(per))
    over = [f"motion {k}" for k, v in enumerate(per, start=1) if v > cap]
    assert 0 < len(over) < 7
    deck = _cabinet(tmp_path, {**qualify, "acceleration_limit_g": {"top": [float(cap), 50.0]}})
    code, err = invoke("qualify", deck, "--out", tmp_path / "mean", "--no-plots", "--statistic", "mean")
    assert code == 0, err
    q = json.loads((tmp_path / "mean" / "qualification.json").read_text())
    c = next(c for c in q["criteria"] if c["item"] == "top x1")
    assert q["statistic"]["used"] == "mean" and c["demand"] == pytest.approx(np.mean(per), rel=1e-12)
    assert c["pass"] and c["over_capacity"] == over and c["per_motion_pass"] == [v <= cap for v in per]
    note = [line for line in err.splitlines() if line.startswith(f"note: acceleration top x1: over {cap:.4g} g in ")]
    assert len(note) == 1 and all(m in note[0] for m in over) and "the mean, the verdict's statistic" in note[0]
    # the default statistic: the largest, so the motions over capacity fail the deck
    code, err = invoke("qualify", deck, "--out", tmp_path / "max", "--no-plots")
    assert code == 1
    q = json.loads((tmp_path / "max" / "qualification.json").read_text())
    c = next(c for c in q["criteria"] if c["item"] == "top x1")
    assert q["statistic"]["asked"] == "max" and c["demand"] == max(per) and not c["pass"] and c["over_capacity"] == over
    fail = [line for line in err.splitlines() if line.startswith("fail: acceleration top x1: ")]
    assert len(fail) == 1 and f"(the max over the motions; over {cap:.4g} g in {len(over)} of 7 motions: " in fail[0]
    assert all(m in fail[0] for m in over)


def test_a_demand_beyond_its_capacity_fails_with_exit_1(tmp_path):
    deck = _cabinet(tmp_path, {"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "seed": 2,
                               "acceleration_limit_g": {"top": 1.0}})
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", "--no-plots")
    assert code == 1
    lines = err.splitlines()
    assert any(line.startswith("fail: acceleration top x1: ") and line.endswith(" g > 1 g") for line in lines)
    assert lines[-2].startswith("verdict: fail: ")
    q = json.loads((tmp_path / "q" / "qualification.json").read_text())
    assert not q["pass"] and not (tmp_path / "q" / "qualification.png").exists()


def test_a_run_that_cannot_vouch_for_its_accuracy_cannot_pass(tmp_path):
    deck = _cabinet(tmp_path, analysis={"dt": 0.005, "integrator": "chang"})  # (named: exactly at that dt)
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", "--no-plots")
    q = json.loads((tmp_path / "q" / "qualification.json").read_text())
    assert code == 1 and not q["pass"] and not q["accuracy"]["pass"]
    assert all(c["pass"] for c in q["criteria"])  # every margin fine, and still no pass
    assert q["accuracy"]["estimated_error"] > q["accuracy"]["warn_error"] and q["warnings"]
    assert any(line.startswith("fail: a run cannot vouch for its accuracy: estimated error ") for line in err.splitlines())


def test_the_decks_own_motion_is_checked_against_the_rrs(tmp_path):
    deck = _cabinet(tmp_path)
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", "--motions", "deck", "--no-plots", "--report")
    q = json.loads((tmp_path / "q" / "qualification.json").read_text())
    # the sample's synthetic records are no AC156 motion at 1 g: their TRS lies far below
    assert code == 1 and not q["trs"]["pass"] and q["motions"][0]["trs"]["x1"]["max_ratio"] < 0.9
    # (no trs.csv without made motions: the console names where the TRS is)
    assert not (tmp_path / "q" / "trs.csv").exists()
    assert ("fail: the motions' TRS is not within the RRS's band (qualification.json, qualification.png)"
            in err.splitlines())
    # its records' strong motion measured as for a made motion's (AC156 asks for 20 s)
    from independent_spectra import bracketed_duration

    for axis in ("x1", "x2"):
        dt, a = _acc_g(DECKS / "records" / f"synthetic_{axis}.csv")
        sm = q["motions"][0]["strong_motion"][axis]
        assert sm["strong_motion_s"] == pytest.approx(bracketed_duration(a, dt), abs=0.05)
        assert sm["strong_motion_min_s"] == 20.0 and sm["strong_motion_pass"] == (sm["strong_motion_s"] >= 20.0)
    assert q["trs"]["strong_motion_pass"] == all(q["motions"][0]["strong_motion"][a]["strong_motion_pass"]
                                                 for a in ("x1", "x2"))
    # its report: every number its files', the TRS of the deck's own motion, and why it fails
    from test_report import check_page

    page = check_page(tmp_path / "q")
    srcs = {a["data-src"] for a, _ in page.numbers}
    assert {f"qualification.json:motions.0.trs.{axis}.{key}" for axis in ("x1", "x2")
            for key in ("min_ratio", "max_ratio", "peak_g")} <= srcs
    text = " ".join(page.text)
    assert "The deck does not qualify to ICC-ES AC156" in text and "the deck's excitation.support" in text
    assert "trs.csv" not in text and "The deck's own motion: peaks and extremes" in text


def test_qualify_against_ieee693_from_the_deck_and_the_command_line(tmp_path):
    deck = _cabinet(tmp_path, {"standard": "ieee693", "level": "moderate", "seed": 3,
                               "acceleration_limit_g": {"top": 3.0}})
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", "--no-plots")
    q = json.loads((tmp_path / "q" / "qualification.json").read_text())
    assert q["standard"] == "ieee693" and q["rrs"]["x1"]["check_range_hz"] == [1.1, 33.0]
    assert q["trs"]["pass"] and q["trs"]["within_band"] and q["trs"]["peak_pass"]
    assert q["trs"]["peak_min_g"] == {"x1": pytest.approx(0.5), "x2": pytest.approx(0.4)}
    assert q["rrs"]["x2"]["source"] == "IEEE Std 693-2005, Figure A.2, vertical 80 %"
    # --standard on the command line replaces the deck's spectrum, its level with it
    code, err = invoke("qualify", deck, "--out", tmp_path / "q2", "--standard", "ac156", "--no-plots")
    assert code == 2 and errors(err) == [
        "error: qualify.sds: required with the AC156 spectrum (S_DS, the design spectral acceleration at short "
        "periods, in g)",
        "error: qualify.z_over_h: required with the AC156 spectrum (z/h, the attachment height over the roof height, "
        "0 at grade to 1 at the roof)"]
    for bad, lines in (
            ({"standard": "ieee693", "level": "extreme"},
             ["error: qualify.level: must be 'high' or 'moderate'"]),
            ({"standard": "ieee693", "sds": 1.0, "rrs_damping": 0.5},
             ["error: qualify.level: required with the IEEE 693 spectrum: high or moderate (its performance level)",
              "error: qualify.rrs_damping: 0.5: IEEE 693's damping factor is used from 0.005 to 0.2 (0.05 by default, "
              "the damping it is matched at)",
              "error: qualify.sds: only with qualify.standard ac156"]),
            ({"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "level": "high"},
             ["error: qualify.level: only with qualify.standard ieee693"]),
            ({"standard": "ieee693", "level": "high", "duration": 20.0},
             ["error: qualify.duration: 20 s: IEEE 693 asks for 20 s of strong motion (ramps of 5 s): "
              "qualify.duration 30 or more"])):
        deck = _cabinet(tmp_path, {**bad, "acceleration_limit_g": {"top": 3.0}})
        code, err = invoke("qualify", deck, "--out", tmp_path / "q3")
        assert code == 2 and errors(err) == lines
    assert not (tmp_path / "q3").exists()


def test_qualify_mistakes_are_one_line_each_and_nothing_is_written(tmp_path):
    deck = _cabinet(tmp_path, {"standard": "ac156", "sds": 1.0, "acceleration_limit_g": {"roof": 2.0},
                               "force_capacity_N": {"e9": 1.0}})
    out = tmp_path / "q"
    out.mkdir()
    (out / "qualification.json").write_text("mine")
    before = snapshot(out)
    code, err = invoke("qualify", deck, "--out", out)
    assert code == 2 and err.splitlines() == [
        "error: qualify.z_over_h: required with the AC156 spectrum (z/h, the attachment height over the roof "
        "height, 0 at grade to 1 at the roof)",
        "error: qualify.acceleration_limit_g.roof: no point 'roof' in output.points (top, G (the mass centre))",
        "error: qualify.force_capacity_N.e9: not an element: e1 to e8, as in time_history.csv (count expanded)"]
    code, err = invoke("qualify", deck, "--out", out, "--z-over-h", "0.5", "--motions", "0")
    assert code == 2 and "error: --motions: 0: at least 1" in err.splitlines()
    code, err = invoke("qualify", _cabinet(tmp_path, {"standard": "ac156", "sds": 1.0, "z_over_h": 0.5,
                                                      "acceleration_limit_g": {"top": 2.0}}), "--out", out)
    assert code == 2 and err.splitlines() == [
        f"error: {out}: qualification.json exists and rbhyst did not write it (not listed in .rbhyst.json); rbhyst "
        "will not overwrite it: move it away or choose another output folder"]
    assert snapshot(out) == before
    cab = tomllib.loads((DECKS / "cabinet_transformer.toml").read_text())
    cab["qualify"] = {"standard": "ac156", "rrs": "x.csv"}
    code, err = invoke("qualify", write_deck(tmp_path, cab, name="both"))
    assert code == 2 and err.splitlines() == [
        "error: qualify.rrs: not with qualify.standard: give a standard or RRS files"]


# ---------------------------------------------------------------- after the motion


def test_a_peak_in_the_free_vibration_after_the_motion_counts(tmp_path):
    """A record that stops while the body swings: the peaks come after it, and a run that
    stopped with the record (as qualification runs did) missed them."""
    import rbhyst

    t = np.arange(0.0, 1.02 + 1e-9, 0.001)
    pulse = np.where(t >= 1.0, 2.0 * np.sin(np.pi * (t - 1.0) / 0.02), 0.0)  # a 20 ms half-sine, last
    (tmp_path / "pulse.csv").write_text("time_s,acceleration_g\n" + "\n".join(f"{a:.6f},{b:.9e}" for a, b in
                                                                               zip(t, pulse)) + "\n")
    deck = _cabinet(tmp_path, {"standard": "ac156", "sds": 1.0, "z_over_h": 0.0, "motions": "deck",
                               "acceleration_limit_g": {"top": 30.0}},
                    excitation={"support": {"x1": {"file": "pulse.csv", "units": "g"}}})
    code, err = invoke("qualify", deck, "--out", tmp_path / "q", "--no-plots")
    q = json.loads((tmp_path / "q" / "qualification.json").read_text())
    run = q["runs"][0]
    s = json.loads((tmp_path / "q" / "run_1" / "summary.json").read_text())
    f1 = s["modes"]["frequencies_hz"][0]
    assert run["motion_end_s"] == pytest.approx(1.02) and run["decayed"], run
    assert run["free_vibration_s"] == pytest.approx(max(2.0, 10.0 / f1), abs=2e-3)
    assert s["analysis"]["duration_s"] == pytest.approx(1.02 + run["free_vibration_s"], abs=1e-9)
    peak_at = max(s["extremes"]["u1_m"].items(), key=lambda kv: abs(kv[1]) if "time" not in kv[0] else 0)[0]
    assert s["extremes"]["u1_m"][f"time_of_{peak_at}_s"] > 1.02  # the peak is in the free vibration
    # ... which the same deck run to the record's end alone did not see, and a run twice as long
    # after it sees no larger
    cab = rbhyst.load_deck(deck)
    short = rbhyst.run(cab.with_values({"analysis.duration": 1.02})).summary()
    long = rbhyst.run(cab.with_values({"analysis.duration": 1.02 + 2 * run["free_vibration_s"]})).summary()
    assert short["peaks"]["u1_m"] < 0.9 * s["peaks"]["u1_m"]
    assert long["peaks"]["u1_m"] == pytest.approx(s["peaks"]["u1_m"], rel=1e-6)
    assert long["peaks"]["top_at1_m_s2"] == pytest.approx(s["peaks"]["top_at1_m_s2"], rel=1e-6)
    assert "free_vibration" in q and "10 periods" in q["free_vibration"]["rule"]


def test_decay_is_judged_on_the_responses_growth_not_the_inputs_nor_the_energies():
    from rbhyst.analyses.qualification.free_vibration import grown, tail_s

    t = np.linspace(0.0, 10.0, 1001)
    cols = {"u1_m": np.sin(t) * np.exp(-t),            # decays: its peak is early
            "u2_m": 0.002 * (1 - np.exp(-t)),          # settles: grows 0.7 % after 5 s
            "u3_m": 1e-12 * t,                         # at rest (rounding)
            "ag1_m_s2": np.where(t > 9, 3.0, 0.0),     # the input, not a response
            "E_input_J": t}                            # accumulates
    assert grown(t, cols, 5.0, 0.01) == []
    got = grown(t, cols, 5.0, 0.001)
    assert [c for c, _ in got] == ["u2_m"] and got[0][1] == pytest.approx((np.exp(-5.0) - np.exp(-10.0)) / (1 - np.exp(-5.0)), rel=1e-9)
    assert tail_s([0.0, 0.5, 7.0]) == 20.0 and tail_s([20.0]) == 2.0 and tail_s([]) == 2.0


# ---------------------------------------------------------------- the table


@pytest.mark.parametrize("options", [
    ("--rrs", "ac156", "--sds", "1.0", "--z-over-h", "0.5", "--seed", "1"),  # 0.23-0.27 m unlimited
    ("--rrs", "ieee693", "--level", "moderate", "--seed", "2"),
])
def test_a_table_limit_is_met_by_every_record(tmp_path, options):
    from independent_spectra import octave_grid, trs

    out = tmp_path / "m"
    code, err = invoke("make-motion", out, *options, "--motions", "2", "--table", "displacement=0.15,velocity=1.0",
                       "--no-plots")
    assert code == 0, err
    rrs = ac156(1.0, 0.5) if "ac156" in options else ieee693("moderate")
    facts = json.loads((out / "motions.json").read_text())["motions"]
    for m in facts:
        for axis in ("x1", "x2"):
            dt, a = _acc_g(out / m["files"][axis])
            v, d = matching.integrate(a * G, dt)
            assert np.ptp(d) <= 0.15 and np.abs(v).max() <= 1.0
            assert m["axes"][axis]["table"]["pass"] and m["axes"][axis]["displacement_peak_to_peak_m"] == \
                pytest.approx(np.ptp(d), rel=1e-9)
            if m["number"] == 1:  # (the TRS still in its band, independently)
                f = octave_grid(*rrs[axis].check_range)
                ratio = trs(a * G, dt, f, 0.05) / rrs[axis](f)
                assert rrs[axis].band[0] <= ratio.min() and ratio.max() <= rrs[axis].band[1]


def test_a_table_no_record_fits_is_exit_3_with_the_limit_and_what_would_fit(tmp_path):
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", "ac156", "--sds", "1.0", "--z-over-h", "0.5",
                       "--table", "displacement=0.03", "--no-plots")
    line, = errors(err)
    assert code == 3 and line.startswith("error: motion 1 (seed 1) cannot be made within the table: x1: the table's "
                                         "displacement limit is 0.03 m peak to peak and the record asks ")
    assert "a table of displacement=" in line and not (tmp_path / "m").exists()
    code, err = invoke("make-motion", tmp_path / "m", "--rrs", "ac156", "--sds", "1.0", "--z-over-h", "0.5",
                       "--table", "acceleration=0.5,stroke=3,velocity=-1", "--no-plots")
    assert code == 2 and errors(err) == [
        "error: --table: 'stroke=3': name=value with displacement (m, peak to peak), velocity (m/s) or acceleration (g)",
        "error: --table: velocity=-1: must be positive (m/s, peak)",
        "error: --table: acceleration=0.5 g is below the least peak the RRS of x1 asks for (0.72 g): no record can "
        "meet both"]
    deck = _cabinet(tmp_path, {"standard": "ac156", "sds": 1.0, "z_over_h": 0.5, "table": {"stroke": 0.2},
                               "acceleration_limit_g": {"top": 3.0}})
    code, err = invoke("qualify", deck, "--out", tmp_path / "q")
    assert code == 2 and len(errors(err)) == 1 and "qualify.table.stroke" in err
