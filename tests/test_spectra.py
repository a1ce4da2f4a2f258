"""Response spectra: the recurrence against closed forms, a 50-digit exponential and a fine
ODE solution; streaming against whole; and against eqsig where it is installed."""

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp

from rbhyst.errors import InputError
from rbhyst.response import SpectrumAccumulator, default_periods, response_spectrum, step_coefficients
from rbhyst.solve.spectra import substep_counts

EPS = np.finfo(float).eps


def sinc2(x):
    """(sin x / x)^2: the gain of linear interpolation at a frequency w for x = w h / 2."""
    return (math.sin(x) / x) ** 2


# --- the step's coefficients -----------------------------------------------------------


def exact_coefficients(omega, zeta, h, digits=50):
    """A11..B22 from exp(M) of the augmented system in 50-digit arithmetic (scaling and
    squaring of its Taylor series): d/ds (x, h x', -h^2 a, -h^2 da) over s = t / h."""
    with localcontext() as ctx:
        ctx.prec = digits
        wh, z, hd = Decimal(omega) * Decimal(h), Decimal(zeta), Decimal(h)
        one, zero = Decimal(1), Decimal(0)
        m = [[zero, one, zero, zero], [-wh * wh, -2 * z * wh, one, zero],
             [zero, zero, zero, one], [zero] * 4]
        squarings = 0
        while max(sum(abs(v) for v in row) for row in m) > Decimal("0.5"):
            m = [[v / 2 for v in row] for row in m]
            squarings += 1

        def mul(p, q):
            return [[sum(p[i][k] * q[k][j] for k in range(4)) for j in range(4)] for i in range(4)]

        e = [[one if i == j else zero for j in range(4)] for i in range(4)]
        term = [row[:] for row in e]
        for k in range(1, 60):
            term = [[v / k for v in row] for row in mul(term, m)]
            e = [[e[i][j] + term[i][j] for j in range(4)] for i in range(4)]
        for _ in range(squarings):
            e = mul(e, e)
        coef = (e[0][0], e[0][1] * hd, e[1][0] / hd, e[1][1], -hd * hd * (e[0][2] - e[0][3]),
                -hd * hd * e[0][3], -hd * (e[1][2] - e[1][3]), -hd * e[1][3])
        return np.array([float(c) for c in coef])


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.3, 0.95])
def test_coefficients_match_a_50_digit_exponential(zeta):
    # omega h from a 10 s oscillator at dt = 0.1 ms (the closed form alone loses 7 digits
    # there) to 1000 (a very short period at a coarse step)
    h = 0.01
    scale = np.array([1, 1 / h, h, 1, 1 / h**2, 1 / h**2, 1 / h, 1 / h])  # to (x, h x', h^2 a)
    for wh in np.geomspace(1e-6, 1e3, 19):
        got = step_coefficients(wh / h, zeta, h) * scale
        ref = exact_coefficients(wh / h, zeta, h) * scale
        # each row's error within a few roundings of the step itself on a unit state; the
        # (1 + wh) is the conditioning of sin(wd h), cos(wd h) on the rounding of wd h
        row = np.repeat([np.abs(ref[[0, 1, 4, 5]]).sum(), np.abs(ref[[2, 3, 6, 7]]).sum()], 2)
        row = np.concatenate([row, row])
        assert np.all(np.abs(got - ref) <= 8 * EPS * (1 + wh) * row), (wh, got - ref)


def test_coefficients_reduce_to_the_free_particle_and_to_a_rotation():
    # omega -> 0: x'' = -a, linear a: x+ = x + h v - h^2 (a/3 + a+/6), v+ = v - h (a + a+)/2
    h = 0.02
    c = step_coefficients(1e-9, 0.0, h)
    assert c == pytest.approx([1, h, 0, 1, -h * h / 3, -h * h / 6, -h / 2, -h / 2], rel=1e-14, abs=1e-17)
    # undamped, no input: a rotation by omega h in (x, x'/omega)
    w = 7.0
    c = step_coefficients(w, 0.0, h)
    assert c[:4] == pytest.approx([math.cos(w * h), math.sin(w * h) / w, -w * math.sin(w * h), math.cos(w * h)],
                                  rel=1e-15)


# --- closed-form responses ---------------------------------------------------------------


def test_undamped_step_peaks_at_twice_the_static_displacement():
    # a(t) = A from t = 0: x = -A/w^2 (1 - cos w t), peak 2 A / w^2 at T/2, which is a
    # point for each period below (a sample, or a substep for T = 0.1 and 0.02 s at dt 0.01 s)
    A, dt = 3.0, 0.01
    periods = np.array([1.0, 0.1, 0.02])
    assert list(substep_counts(periods, dt, 20)) == [1, 2, 10]
    spec = response_spectrum(np.full(400, A), dt, periods, dampings=[0.0])
    w = 2 * np.pi / periods
    assert spec.sd[:, 0, 0] == pytest.approx(2 * A / w**2, rel=1e-12)
    assert spec.sa[:, 0, 0] == pytest.approx(2 * A, rel=1e-12)
    # no damping: the absolute acceleration is -w^2 x, the same peak as psa to the last bit
    assert np.array_equal(spec.sa, spec.psa)


def test_resonant_sine_envelope_grows_linearly():
    # x'' + w^2 x = -B sin w t from rest: x = B/(2 w^2) (w t cos w t - sin w t), whose
    # peaks |x| = B k pi / (2 w^2) fall at t = k T/2. Linear interpolation of the samples
    # passes the frequency w with gain sinc^2(w h/2) and no phase shift, so B = A sinc^2;
    # its aliases near 2 pi / h add less than 1e-7 A / w^2 (see the test's bound below).
    A, T, per_period = 2.0, 0.5, 100
    w, h = 2 * np.pi / T, T / per_period
    half = per_period // 2
    t = h * np.arange(20 * half + 1)
    acc = A * np.sin(w * t)
    stream = SpectrumAccumulator([T], [0.0], 1, h)
    stream.update(acc[:1])
    B = A * sinc2(w * h / 2)
    for k in range(1, 21):
        stream.update(acc[1 + (k - 1) * half: 1 + k * half])  # up to and including t = k T/2
        sd = stream.result().sd[0, 0, 0]
        # alias bound: sum over k != 0 of 2 sin^2(wh/2) / (pi k + wh/2)^2 / ((1 + k per_period)^2 - 1),
        # in units of A / w^2: 4e-8 here
        assert abs(sd - B * k * np.pi / (2 * w**2)) < 1e-7 * A / w**2, k
    # the piecewise-linear input is what is solved: the sine itself would give 3.3e-4 more
    assert abs(sd / (A * 20 * np.pi / (2 * w**2)) - 1) > 3e-4


@pytest.mark.parametrize("zeta", [0.05, 0.2])
def test_damped_steady_state_amplitudes(zeta):
    # a = A sin(W t): in the steady state |x| = A / w^2 H(r), |x'' + a| = A H(r) sqrt(1 + (2 zeta r)^2),
    # H = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2), r = W / w. Sampled at h: the input's gain at W
    # is sinc^2(W h/2) and a peak between two points is at most W h / 2 away from one, so the
    # maximum over the points lies in [cos(W h / 2), 1] x the amplitude
    A, f_in, per_cycle = 1.5, 1.0, 2000
    big_w, h = 2 * np.pi * f_in, 1.0 / (f_in * per_cycle)
    r = np.array([0.5, 0.8, 1.0, 1.25, 2.0])
    periods = r / f_in
    w = 2 * np.pi / periods
    settle = 25 / (zeta * w.min())  # transients down to exp(-25) = 1e-11
    n_settle = int(np.ceil(settle * f_in)) * per_cycle
    t = h * np.arange(n_settle + 10 * per_cycle + 1)
    acc = A * np.sin(big_w * t)
    stream = SpectrumAccumulator(periods, [zeta], 1, h)
    stream.update(acc[: n_settle + 1])
    stream.reset_peaks()
    stream.update(acc[n_settle + 1:])
    spec = stream.result()
    gain = sinc2(big_w * h / 2)
    H = 1 / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    for got, amplitude in ((spec.sd[:, 0, 0], A / w**2 * H), (spec.sa[:, 0, 0], A * H * np.sqrt(1 + (2 * zeta * r) ** 2))):
        ratio = got / (gain * amplitude)
        assert np.all(ratio <= 1 + 1e-9) and np.all(ratio >= math.cos(big_w * h / 2) - 1e-9), ratio


# --- against an ODE solver ---------------------------------------------------------------


@pytest.mark.slow
def test_running_peaks_match_a_fine_ode_solution():
    # a random piecewise-linear input, each segment integrated by DOP853 at rtol 1e-12 from
    # the end state of the last; fed one sample at a time, the running peaks compare after
    # every sample with the peaks of the ODE's solution at the recurrence's own points (the
    # substeps of the short periods included: never below them) and between them (200 points
    # a substep: the parabolas through the points recover most of what the points miss)
    rng = np.random.default_rng(7)
    dt, n = 0.01, 120
    acc = rng.normal(0.0, 3.0, n)
    periods = np.array([0.004, 0.03, 0.2, 1.0, 4.0])  # the first two below 20 dt: 50 and 7 substeps
    dampings = np.array([0.0, 0.05, 0.3])
    m = substep_counts(periods, dt, 20)
    assert list(m) == [50, 7, 1, 1, 1]
    stream = SpectrumAccumulator(periods, dampings, 1, dt)
    sd_run = np.empty((n, len(periods), len(dampings)))
    sa_run = np.empty_like(sd_run)
    for i in range(n):
        stream.update(acc[i:i + 1])
        spec = stream.result()
        sd_run[i], sa_run[i] = spec.sd[:, :, 0], spec.sa[:, :, 0]
    dense = 200
    gained = missed = 0.0
    for j, (T, mj) in enumerate(zip(periods, m)):
        w = 2 * np.pi / T
        c, k = 2 * dampings * w, w * w  # the three dampings at once: y = (x1, x2, x3, v1, v2, v3)
        y = np.zeros(6)
        peaks = {"points": [np.zeros(3), np.zeros(3)], "dense": [np.zeros(3), np.zeros(3)]}
        for i in range(n - 1):
            a0, a1 = acc[i], acc[i + 1]

            def rhs(t, y, a0=a0, a1=a1):
                return np.concatenate([y[3:], -c * y[3:] - k * y[:3] - (a0 + (a1 - a0) * t / dt)])

            sol = solve_ivp(rhs, (0.0, dt), y, method="DOP853", rtol=1e-12, atol=1e-16,
                            t_eval=dt * np.arange(1, mj * dense + 1) / (mj * dense))
            y = sol.y[:, -1]
            for name, every in (("points", dense), ("dense", 1)):
                x, v = sol.y[:3, every - 1::every], sol.y[3:, every - 1::every]
                pk = peaks[name]
                pk[0] = np.maximum(pk[0], np.abs(x).max(axis=1))
                pk[1] = np.maximum(pk[1], np.abs(c[:, None] * v + k * x).max(axis=1))
            for q, run in ((0, sd_run), (1, sa_run)):
                got, low, top = run[i + 1, j], peaks["points"][q], peaks["dense"][q]
                assert np.all(got >= low * (1 - 1e-9)), (T, i)
                assert np.all(np.abs(got - top) <= 2e-3 * top), (T, i, got, low, top)  # the points alone: 19 % here
                gained += float(np.sum(got - low))
                missed += float(np.sum(top - low))
    assert gained > 0.98 * missed  # what the points alone would miss is found


@pytest.mark.parametrize("per_period", [20.3, 20.5, 21.7, 25.0])
def test_a_sinusoid_peaks_between_its_points_within_3e_5(per_period):
    """An undamped oscillator under a step input swings between 0 and 2 A / w^2 (x) and
    between 0 and 2 A (the absolute acceleration), its peaks between the points: the cubics
    through the points find them within 3e-5, where the points alone miss up to 1.2 %."""
    T, A = 1.0, 1.0
    dt = T / per_period
    w = 2 * np.pi / T
    acc = np.full(int(3 * per_period), A)
    spec = response_spectrum(acc, dt, [T], [0.0])
    points = response_spectrum(acc, dt, [T], [0.0], points_per_period=0)
    assert spec.sd[0, 0, 0] == pytest.approx(2 * A / w**2, rel=3e-5)
    assert spec.sa[0, 0, 0] == pytest.approx(2 * A, rel=3e-5)
    assert points.sd[0, 0, 0] < 2 * A / w**2 * (1 - 1e-4)  # (what the points alone give)


def test_substeps_find_the_peaks_that_samples_miss():
    # T = dt / 2: the samples see the oscillator at the same phase; the substeps do not
    dt, T = 0.01, 0.005
    A = 1.0
    spec_fine = response_spectrum(np.full(200, A), dt, [T], [0.0])
    spec_samples = response_spectrum(np.full(200, A), dt, [T], [0.0], points_per_period=0)
    w = 2 * np.pi / T
    assert spec_fine.sd[0, 0, 0] == pytest.approx(2 * A / w**2, rel=1e-12)
    # x = -A/w^2 (1 - cos w t) at t = 2k T: exactly 0 (rounding only)
    assert spec_samples.sd[0, 0, 0] < 1e-9 * A / w**2


# --- streaming ---------------------------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(0, 97), min_size=1, max_size=12), st.integers(0, 2**31 - 1))
def test_any_chunking_gives_the_whole_answer_to_the_bit(cuts, seed):
    rng = np.random.default_rng(seed)
    dt = 0.005
    acc = rng.normal(0.0, 2.0, (97, 3))
    periods = np.array([0.002, 0.01, 0.05, 0.3, 2.0])  # 50, 10, 2 substeps and none
    whole = response_spectrum(acc, dt, periods, [0.0, 0.05])
    stream = SpectrumAccumulator(periods, [0.0, 0.05], 3, dt)
    edges = [0, *sorted(cuts), len(acc)]
    for lo, hi in zip(edges[:-1], edges[1:]):
        stream.update(acc[lo:hi])  # empty chunks included
    part = stream.result()
    assert part.samples == whole.samples == 97
    assert np.array_equal(part.sd, whole.sd) and np.array_equal(part.sa, whole.sa)


def test_signals_and_oscillators_keep_their_places():
    # each (period, damping, signal) entry equals a run of that oscillator on that signal alone
    rng = np.random.default_rng(3)
    dt = 0.01
    acc = rng.normal(0.0, 1.0, (150, 2))
    periods, dampings = [0.05, 0.015, 1.0], [0.02, 0.1]
    spec = response_spectrum(acc, dt, periods, dampings)
    assert spec.sd.shape == spec.sa.shape == spec.psa.shape == (3, 2, 2)
    for j, T in enumerate(periods):
        for k, z in enumerate(dampings):
            for s in range(2):
                one = response_spectrum(acc[:, s], dt, [T], [z])
                assert one.sd[0, 0, 0] == spec.sd[j, k, s] and one.sa[0, 0, 0] == spec.sa[j, k, s]


# --- inputs ------------------------------------------------------------------------------


def test_default_periods():
    t = default_periods()
    assert len(t) == 100 and t[0] == 0.01 and t[-1] == 10.0
    assert np.allclose(np.diff(np.log(t)), math.log(1000) / 99, rtol=1e-12)


def test_bad_arguments_are_input_errors_one_line_each():
    with pytest.raises(InputError) as err:
        SpectrumAccumulator([1.0, -0.5, float("nan")], [0.05, 1.0], 1, 0.01)
    assert err.value.problems == ["periods: -0.5 s must be positive and finite",
                                  "periods: nan s must be positive and finite",
                                  "dampings: 1.0 must be at least 0 and below 1 (an underdamped oscillator)"]
    stream = SpectrumAccumulator([1.0], [0.05], 2, 0.01)
    stream.update(np.zeros((5, 2)))
    bad = np.zeros((4, 2))
    bad[2, 1] = np.inf
    with pytest.raises(InputError, match=r"sample 8 of signal 2 is inf"):
        stream.update(bad)
    with pytest.raises(InputError, match=r"shape \(4, 3\)"):
        stream.update(np.zeros((4, 3)))
    assert stream.samples == 5  # a refused chunk changes nothing


def test_fewer_than_two_samples_leave_the_oscillators_at_rest():
    for acc in (np.zeros(0), np.array([5.0])):
        spec = response_spectrum(acc, 0.01, [0.5], [0.05])
        assert spec.samples == len(acc) and spec.sd[0, 0, 0] == 0.0 and spec.sa[0, 0, 0] == 0.0


# --- another implementation ----------------------------------------------------------------


def test_agrees_with_eqsig():
    eqsig = pytest.importorskip("eqsig")
    rng = np.random.default_rng(11)
    dt = 0.01
    acc = np.convolve(rng.normal(0.0, 2.0, 2000), np.ones(5) / 5, mode="same")
    periods = np.geomspace(0.2, 5.0, 12)  # omega dt >= 0.012: eqsig's closed form keeps 11 digits
    ours = response_spectrum(acc, dt, periods, [0.05], points_per_period=0)
    # eqsig takes omega = 6.2831853 / T: give it the periods that make its omega ours
    x, _, abs_acc = eqsig.sdof.response_series(acc, dt, periods * 6.2831853 / (2 * np.pi), 0.05)
    assert ours.sd[:, 0, 0] == pytest.approx(np.abs(x).max(axis=1), rel=1e-10)
    assert ours.sa[:, 0, 0] == pytest.approx(np.abs(abs_acc).max(axis=1), rel=1e-10)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.2])
def test_agrees_with_scipys_first_order_hold(zeta):
    """scipy.signal.lsim with its default linear interpolation discretises the same ODE exactly
    for an input linear between samples (via a matrix exponential, not Nigam-Jennings' closed
    form): an independent implementation of the same answer."""
    from scipy import signal

    rng = np.random.default_rng(5)
    dt = 0.01
    acc = np.convolve(rng.normal(0.0, 2.0, 1500), np.ones(4) / 4, mode="same")
    periods = np.geomspace(0.25, 4.0, 7)
    ours = response_spectrum(acc, dt, periods, [zeta], points_per_period=0)
    t = dt * np.arange(len(acc))
    for i, period in enumerate(periods):
        w = 2 * np.pi / period
        a = [[0.0, 1.0], [-w * w, -2 * zeta * w]]
        c = [[1.0, 0.0], [-w * w, -2 * zeta * w]]  # x, and the absolute acceleration x'' + a
        sys = signal.StateSpace(a, [[0.0], [-1.0]], c, [[0.0], [0.0]])
        _, y, _ = signal.lsim(sys, acc, t)
        assert ours.sd[i, 0, 0] == pytest.approx(np.abs(y[:, 0]).max(), rel=1e-11), period
        assert ours.sa[i, 0, 0] == pytest.approx(np.abs(y[:, 1]).max(), rel=1e-11), period
