"""Shock response spectra of a run ([output.spectra] kind = "srs").

The oscillators are tested in test_shock_spectra.py; what a run adds is which accelerations reach
them and where the primary spectrum ends: the ground's is its signal's, G's and the points' are
their columns' at every compute step, primary up to the excitation's end and residual after it.
The check of the body is independent: a body whose x1 motion is a linear undamped oscillator of
its own, and an oscillator of the spectrum on it, integrated together by solve_ivp in the test.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

import rbhyst
from rbhyst.cli import app
from rbhyst.solve.located_shock import RUN_SRS_COLUMNS
from rbhyst.solve.shock_spectra import ShockAccumulator, shock_spectrum
from conftest import write_deck

G = 9.80665
A_G, WIDTH, START = 10.0, 0.011, 0.01  # a 10 g 11 ms half-sine, from 10 ms
KB, MASS = 30000.0, 150.0  # each of two linear horizontal elements at G: w0^2 = 2 KB / MASS


def box(kind_keys: dict, duration: float = 1.5) -> dict:
    """A box whose horizontal elements act at G (x1 is a linear oscillator of its own: no rocking)
    on linear laws (f0 = 0), with vertical ones at its feet, under a half-sine along x1."""
    linear = {"kb": KB, "f0": 0.0, "alpha": 100.0}
    vertical = {"kb": 8.0e4, "f0": 0.0, "alpha": 100.0}
    return {
        "title": "box on linear mounts under a half-sine",
        "body": {"vertices": [[-0.3, -0.4], [0.3, -0.4], [0.3, 0.4], [-0.3, 0.4]], "mass": MASS},
        "hysteresis": {"h": {"loading": linear, "unloading": linear},
                       "v": {"loading": vertical, "unloading": vertical}},
        "elements": [{"point": [0.0, 0.0], "angle_deg": 0.0, "hysteresis": "h"},
                     {"point": [0.0, 0.0], "angle_deg": 180.0, "hysteresis": "h"},
                     {"vertex": 1, "angle_deg": 90.0, "hysteresis": "v"},
                     {"vertex": 2, "angle_deg": 90.0, "hysteresis": "v"}],
        "excitation": {"support": {"x1": {"type": "half-sine", "amplitude": A_G, "units": "g",
                                          "duration": WIDTH, "start": START}}},
        "analysis": {"dt": 2.0e-4, "duration": duration},
        "output": {"points": [{"name": "top", "point": [0.0, 0.4]}], "spectra": {"kind": "srs", **kind_keys}},
    }


def half_sine(t):
    a = A_G * G * np.sin(math.pi * (t - START) / WIDTH)
    return np.where((t >= START) & (t <= START + WIDTH), a, 0.0)


def independent_srs_of_g(f_hz: float, q: float, t_end: float) -> tuple[float, float, float, float]:
    """(primary +, primary -, residual +, residual -) of the oscillator f_hz, Q on G along x1: the
    body's x1 (u'' = -w0^2 u - ag) and the oscillator (x'' = -2 z w x' - w^2 x - aG, aG = -w0^2 u)
    integrated together, piece by piece between the pulse's corners."""
    w0s = 2.0 * KB / MASS
    w, z = 2.0 * math.pi * f_hz, 1.0 / (2.0 * q)

    def rhs(t, y):
        u, v, x, xd = y
        ag = A_G * G * math.sin(math.pi * (t - START) / WIDTH) if START <= t <= START + WIDTH else 0.0
        a_g = -w0s * u
        return [v, -w0s * u - ag, xd, -2.0 * z * w * xd - w * w * x - a_g]

    y = [0.0, 0.0, 0.0, 0.0]
    peaks = []
    for lo, hi in ((0.0, START), (START, START + WIDTH), (START + WIDTH, t_end)):
        t = np.linspace(lo, hi, max(3, int((hi - lo) / 1e-5)))
        sol = solve_ivp(rhs, (lo, hi), y, t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
        absolute = -(2.0 * z * w * sol.y[3] + w * w * sol.y[2])
        peaks.append((float(absolute.max()), float(-absolute.min())))
        y = sol.y[:, -1]
    primary = (max(peaks[0][0], peaks[1][0]), max(peaks[0][1], peaks[1][1]))
    return primary[0], primary[1], peaks[2][0], peaks[2][1]


def test_gs_shock_spectrum_is_the_oscillator_on_the_body(tmp_path):
    d = box({"q": [10.0, 50.0], "range_hz": [4.0, 64.0], "per_octave": 1})
    d["analysis"]["tolerance"] = 1e-5  # the body's own error below what the spectrum is checked to
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    s = res.spectra.of("G", "x1")
    np.testing.assert_allclose(s.frequencies_hz, [4.0, 8.0, 16.0, 32.0, 64.0])
    assert res.spectra.switch == pytest.approx(START + WIDTH)
    for i in (0, 1, 3):  # below, near and above the body's own 3.18 Hz
        for j, q in enumerate((10.0, 50.0)):
            pp, pn, rp, rn = independent_srs_of_g(float(s.frequencies_hz[i]), q, 1.5)
            got = (s.primary_positive[i, j], s.primary_negative[i, j], s.residual_positive[i, j],
                   s.residual_negative[i, j])
            scale = max(pp, pn, rp, rn)
            for mine, theirs in zip(got, (pp, pn, rp, rn)):
                assert abs(mine - theirs) < 5e-5 * scale, (s.frequencies_hz[i], q, got, (pp, pn, rp, rn))


def test_the_grounds_residual_is_the_closed_form(tmp_path):
    """A half-sine's undamped residual spectrum (Harris, Shock and Vibration Handbook, ch. 8):
    2 A W w |cos(w T / 2)| / |W^2 - w^2| with W = pi / T; Q = 1e4 is undamped to 1e-4 here."""
    d = box({"q": 1.0e4, "range_hz": [5.0, 500.0], "per_octave": 3}, duration=0.6)
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    s = res.spectra.of("ground", "x1")
    w = 2.0 * math.pi * s.frequencies_hz
    big_w = math.pi / WIDTH
    closed = 2.0 * A_G * G * big_w * w * np.abs(np.cos(w * WIDTH / 2.0)) / np.abs(big_w ** 2 - w ** 2)
    shown = closed > 0.05 * closed.max()  # (near a zero of the residual the relative error is meaningless)
    np.testing.assert_allclose(s.residual[shown, 0], closed[shown], rtol=2e-3)
    # and its primary is the record's own spectrum, sampled apart from the run's route to it
    t = np.linspace(0.0, START + WIDTH, 20_001)
    alone = shock_spectrum(half_sine(t), t[1] - t[0], s.frequencies_hz, [1.0 / 2e4])
    np.testing.assert_allclose(s.primary[:, 0], alone.primary[:, 0], rtol=1e-4)


def test_the_points_spectra_are_their_columns(tmp_path):
    """With no split step the body's spectra are exactly their columns' (rows at every step)."""
    d = box({"range_hz": [2.0, 200.0]}, duration=0.8)
    d["analysis"]["integrator"] = "chang"
    d["analysis"]["dt"] = 1.0e-4
    d["excitation"]["support"]["x1"]["duration"] = 0.012  # a multiple of dt: no step is split
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    assert res.stats.record_substeps == 1 and res.settings.refine == 1
    t = res.column("time_s")
    for loc, direction, column in (("G", "x1", "at1_m_s2"), ("top", "x1", "top_at1_m_s2"),
                                   ("top", "x2", "top_at2_m_s2")):
        acc = ShockAccumulator(res.spectra.of(loc, direction).frequencies_hz, [0.05], 1, 1.0e-4)
        acc.update_until(res.column(column)[:, None], None, t, START + 0.012)
        own = acc.result()[0]
        mine = res.spectra.of(loc, direction)
        for name in ("primary_positive", "primary_negative", "residual_positive", "residual_negative", "sd"):
            np.testing.assert_array_equal(getattr(mine, name), getattr(own, name))


def test_the_run_writes_srs_csv_and_its_figures(tmp_path):
    d = box({"range_hz": [2.0, 200.0], "per_octave": 6}, duration=0.8)
    out = tmp_path / "out"
    res = rbhyst.run(write_deck(tmp_path, d), out=out)
    assert (out / "srs.png").is_file() and (out / "pvss.png").is_file() and not (out / "spectra.csv").exists()
    with open(out / "srs.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == RUN_SRS_COLUMNS
    located = {(r[0], r[1]) for r in rows[1:]}
    assert located == {("ground", "x1"), ("G", "x1"), ("G", "x2"), ("top", "x1"), ("top", "x2")}
    n_f = len(res.spectra.of("G", "x1").frequencies_hz)
    assert len(rows) - 1 == 5 * n_f
    summary = json.loads((out / "summary.json").read_text())
    assert summary["spectra"]["kind"] == "srs" and summary["spectra"]["file"] == "srs.csv"
    # the estimate measures the body's spectra as it measures the response spectra
    errors = summary["accuracy"]["estimated_error"]
    assert {"srs_G_x1", "srs_top_x1"} <= set(errors) and all(errors[k] < 0.01 for k in ("srs_G_x1", "srs_top_x1"))
    pv = np.array([float(r[RUN_SRS_COLUMNS.index("pv_m_s")]) for r in rows[1:]])
    sd = np.array([float(r[RUN_SRS_COLUMNS.index("sd_m")]) for r in rows[1:]])
    f = np.array([float(r[RUN_SRS_COLUMNS.index("frequency_hz")]) for r in rows[1:]])
    np.testing.assert_allclose(pv, 2.0 * math.pi * f * sd, rtol=1e-9)
    r = CliRunner().invoke(app, ["report", str(out)])
    assert r.exit_code == 0, r.output
    page = (out / "report.html").read_text()
    assert "Shock response spectra: largest maximax" in page and "srs.png" in page and "pvss.png" in page


def test_a_sine_without_end_has_no_residual(tmp_path):
    d = box({"range_hz": [2.0, 20.0]}, duration=0.5)
    d["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.1, "units": "g", "frequency_hz": 3.0}}}
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    s = res.spectra.of("G", "x1")
    assert np.isnan(s.residual).all() and np.array_equal(s.maximax, s.primary)
    assert any("no residual spectrum" in n for n in res.notes)


def test_a_short_analysis_says_the_residual_needs_longer(tmp_path):
    d = box({"range_hz": [2.0, 20.0]}, duration=0.2)
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    note = [n for n in res.notes if "residual" in n]
    assert note and "analysis.duration = 0.5" in note[0]  # 0.021 s + one damped period of 2 Hz


@pytest.mark.parametrize("spectra, wrong", [
    ({"kind": "sa", "q": 10.0}, "q: not with kind = 'sa'"),
    ({"kind": "srs", "damping": 0.05}, "damping: not with kind = 'srs'"),
    ({"kind": "srs", "periods_s": [0.1]}, "periods_s: not with kind = 'srs'"),
    ({"kind": "srs", "range_hz": [20.0, 2.0]}, "the lower first"),
    ({"kind": "srs", "q": 0.5}, "greater than 0.5"),
    ({"kind": "psd"}, "kind"),
])
def test_keys_of_the_other_kind_are_refused(tmp_path, spectra, wrong):
    d = box({})
    d["output"]["spectra"] = spectra
    r = CliRunner().invoke(app, ["run", str(write_deck(tmp_path, d)), "--out", str(tmp_path / "out")])
    assert r.exit_code == 2, r.output
    assert "output.spectra" in r.output and wrong in r.output and "Traceback" not in r.output
    assert not (tmp_path / "out").exists()
