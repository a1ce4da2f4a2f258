"""Shock response spectra (rbhyst.solve.shock_spectra, ``rbhyst spectrum --kind srs``) against the
closed-form spectra of a half-sine and an SDOF integration written here."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import invoke
from scipy.integrate import solve_ivp

from rbhyst.solve.shock_spectra import SRS_COLUMNS, octave_frequencies, shock_spectrum


def half_sine_samples(amplitude: float, width: float, per_pulse: int = 2000):
    dt = width / per_pulse
    t = np.arange(per_pulse + 1) * dt
    return amplitude * np.sin(np.pi * t / width), dt


def undamped_half_sine_srs(amplitude: float, width: float, f: float) -> tuple[float, float, float]:
    """Primary positive, primary negative and residual peak absolute acceleration of an undamped
    oscillator under A sin(pi t / T), 0 <= t <= T, in closed form.

    x'' + w^2 x = -a; the absolute acceleration is -w^2 x. During the pulse (W = pi / T, w != W)
    it is A w^2 / (w^2 - W^2) (sin W t - (W / w) sin w t), whose slope vanishes where
    cos W t = cos w t: t = 2 pi n / (w + W) and t = 2 pi n / |w - W|; the primary peaks are the
    largest of it there and at t = T. After the pulse the oscillator swings freely with the
    amplitude w |F(w)|, F the Fourier transform of the pulse: |F(w)| = 2 A W |cos(w T / 2)| /
    |W^2 - w^2| (e.g. Harris' Shock and Vibration Handbook, ch. 8, the residual spectrum of a
    half-sine), so the residual is 2 A W w |cos(w T / 2)| / |W^2 - w^2|.
    """
    w, big_w = 2.0 * math.pi * f, math.pi / width
    times = [width]
    for n in range(1, 10_000):
        for t in (2.0 * math.pi * n / (w + big_w), 2.0 * math.pi * n / abs(w - big_w)):
            if t <= width:
                times.append(t)
        if 2.0 * math.pi * n / (w + big_w) > width:
            break
    t = np.array(times)
    acc = amplitude * w * w / (w * w - big_w * big_w) * (np.sin(big_w * t) - big_w / w * np.sin(w * t))
    residual = 2.0 * amplitude * big_w * w * abs(math.cos(w * width / 2.0)) / abs(big_w ** 2 - w ** 2)
    return float(max(acc.max(), 0.0)), float(max(-acc.min(), 0.0)), residual


@pytest.mark.parametrize("amplitude, width", [(196.133, 0.011), (490.0, 0.006), (30.0, 0.05)])
def test_an_undamped_half_sine_has_its_closed_form_primary_and_residual(amplitude, width):
    acc, dt = half_sine_samples(amplitude, width)
    # frequencies that avoid w = W exactly (the closed form's removable singularity)
    f = octave_frequencies(0.1 / width, 100.0 / width, 12) * (1.0 + 1e-3)
    srs = shock_spectrum(acc, dt, f, [0.0])
    expect = np.array([undamped_half_sine_srs(amplitude, width, fi) for fi in f])
    # a spectrum's near-zeros (the residual vanishes where cos(w T / 2) = 0) are compared with the pulse's peak
    for got, want in ((srs.primary_positive[:, 0], expect[:, 0]), (srs.primary_negative[:, 0], expect[:, 1]),
                      (srs.residual_positive[:, 0], expect[:, 2]), (srs.residual_negative[:, 0], expect[:, 2])):
        assert np.max(np.abs(got - want) / np.maximum(want, 0.01 * amplitude)) < 1e-3
    # undamped, the absolute acceleration is -w^2 x: the displacement spectrum and the PVSS follow
    w = 2.0 * np.pi * f
    assert np.allclose(srs.sd[:, 0] * w * w, srs.maximax[:, 0], rtol=1e-6)
    assert np.allclose(srs.pv[:, 0], w * srs.sd[:, 0], rtol=1e-12)
    # the residual spectrum of a half-sine peaks at 1.77 A near f T = 0.8 (the classic curve)
    assert 1.7 * amplitude < srs.residual.max() < 1.8 * amplitude


def sdof_peaks(signal, end: float, f: float, zeta: float, tail: float):
    """Peaks of the absolute acceleration (positive, negative: before and after ``end``) and of
    |x| of x'' + 2 zeta w x' + w^2 x = -a(t), integrated by scipy's DOP853 at tight tolerances
    with the pulse's formula (not its samples), read on a fine grid and refined by the dense output."""
    w = 2.0 * math.pi * f

    def rhs(t, y):
        return [y[1], -signal(t) - 2.0 * zeta * w * y[1] - w * w * y[0]]

    out = []
    y0 = [0.0, 0.0]
    for lo, hi in ((0.0, end), (end, end + tail)):
        sol = solve_ivp(rhs, (lo, hi), y0, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
        t = np.linspace(lo, hi, 20_001)
        x, v = sol.sol(t)
        a = -(2.0 * zeta * w * v + w * w * x)
        out.append((a.max(), -a.min(), np.abs(x).max()))
        y0 = sol.y[:, -1]
    return out


@pytest.mark.parametrize("f", [15.0, 45.0, 90.0, 300.0])
def test_a_damped_half_sine_agrees_with_an_independent_integration(f):
    amplitude, width, zeta = 196.133, 0.011, 0.05
    acc, dt = half_sine_samples(amplitude, width)
    srs = shock_spectrum(acc, dt, [f], [zeta])
    td = 1.0 / (f * math.sqrt(1.0 - zeta ** 2))
    (pp, pn, psd), (rp, rn, rsd) = sdof_peaks(lambda t: amplitude * math.sin(math.pi * t / width) if t <= width
                                              else 0.0, width, f, zeta, 1.5 * td)
    scale = amplitude
    for got, want in ((srs.primary_positive, pp), (srs.primary_negative, pn), (srs.residual_positive, rp),
                      (srs.residual_negative, rn)):
        assert abs(float(got[0, 0]) - want) < 1e-3 * max(want, 0.01 * scale)
    assert srs.sd[0, 0] == pytest.approx(max(psd, rsd), rel=1e-3)


def test_positive_and_negative_swap_when_the_pulse_does():
    acc, dt = half_sine_samples(100.0, 0.01)
    f = octave_frequencies(10.0, 1000.0, 6)
    up, down = shock_spectrum(acc, dt, f, [0.05]), shock_spectrum(-acc, dt, f, [0.05])
    assert np.array_equal(up.primary_positive, down.primary_negative)
    assert np.array_equal(up.residual_negative, down.residual_positive)
    assert np.array_equal(up.maximax, down.maximax)


def test_octave_frequencies():
    f = octave_frequencies(10.0, 2000.0, 12)
    assert f[0] == 10.0 and f[-1] == 2000.0
    assert np.allclose(f[1:-1] / f[:-2], 2.0 ** (1.0 / 12.0))
    assert len(octave_frequencies(10.0, 80.0, 3)) == 10  # three octaves exactly: 3 x 3 + 1


def test_spectrum_kind_srs_writes_its_files(tmp_path):
    acc, dt = half_sine_samples(20.0, 0.011, 220)
    t = np.arange(len(acc)) * dt
    rec = tmp_path / "hs.csv"
    np.savetxt(rec, np.column_stack([t, acc]), delimiter=",", header="time_s,acceleration_g", comments="")
    out = tmp_path / "o"
    code, err = invoke("spectrum", rec, "--units", "g", "--kind", "srs", "--q", "10,50",
                       "--frequencies", "5..500", "--per-octave", "6", "--out", out)
    assert code == 0, err
    lines = (out / "srs.csv").read_text().splitlines()
    assert lines[0] == ",".join(SRS_COLUMNS)
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert len(rows) == 2 * len(octave_frequencies(5.0, 500.0, 6))
    assert set(rows[:, 0]) == {10.0, 50.0} and set(rows[:, 1]) == {0.05, 0.01}
    mine = rows[rows[:, 0] == 10.0]
    srs = shock_spectrum(acc * 9.80665, dt, mine[:, 2], [0.05])
    assert np.allclose(mine[:, 3], srs.maximax[:, 0], rtol=1e-9)
    assert np.allclose(mine[:, 13], srs.pv[:, 0], rtol=1e-9)
    assert (out / "srs.png").stat().st_size > 0 and (out / "pvss.png").stat().st_size > 0


@pytest.mark.parametrize("args, said", [
    (["--kind", "srs", "--damping", "0.05"], "--damping: not with --kind srs"),
    (["--q", "10"], "--q: not with --kind rs"),
    (["--kind", "srs", "--frequencies", "10-200"], "--frequencies: '10-200': F1..F2"),
    (["--kind", "srs", "--frequencies", "200..10"], "--frequencies: 200..10 Hz"),
    (["--kind", "srs", "--q", "0.3"], "--q: 0.3 must be above 0.5"),
    (["--kind", "psd"], "--kind: 'psd'"),
])
def test_spectrum_kind_srs_mistakes(tmp_path, args, said):
    rec = tmp_path / "r.csv"
    rec.write_text("time_s,acceleration_g\n0,0\n0.001,1\n0.002,0\n")
    code, err = invoke("spectrum", rec, "--units", "g", "--out", tmp_path / "o", *args)
    assert code == 2
    assert said in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()
