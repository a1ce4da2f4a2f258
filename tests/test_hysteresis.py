"""VRM (seed eqs. 14-17): closed form against its rate equation, tangent, work, Table 1 loops."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rbhyst.model import hysteresis as hy
from rbhyst.model.hysteresis import limiting_curve, parameter_set
from rbhyst.model.vrm import loop
from rbhyst.model import vrm
from conftest import TABLE1, TABLE3_AXIAL, TABLE3_SHEAR


def pset(d):
    return parameter_set(d["loading"], d["unloading"])


def sine_history(amplitude=1.5, cycles=3, n=4000):
    t = np.linspace(0.0, cycles, cycles * n + 1)
    return t, amplitude * np.sin(2 * np.pi * t)


SETS = {**{f"table1_{k}": v for k, v in TABLE1.items()}, "table3_axial": TABLE3_AXIAL,
        "table3_shear": TABLE3_SHEAR}
AMPLITUDE = {"table3_axial": 0.01, "table3_shear": 0.01}


@pytest.mark.parametrize("name", sorted(SETS))
def test_closed_form_matches_the_rate_equation(name):
    """Integrate df/du = k_t(u, f) (eq. 16 with the current point as P) branch by branch."""
    p = pset(SETS[name])
    amp = AMPLITUDE.get(name, 1.5)
    u = np.concatenate([np.linspace(0, amp, 301), np.linspace(amp, -amp, 601)[1:],
                        np.linspace(-amp, 0.3 * amp, 401)[1:]])
    f, _, _ = loop(p, u)
    f_ode = [0.0]
    turns = [0, 300, 900, len(u) - 1]
    fcur = 0.0
    for i0, i1 in zip(turns[:-1], turns[1:]):
        s = 1.0 if u[i1] > u[i0] else -1.0
        row = 0 if s > 0 else 1
        alpha = p[row, 2]

        def rate(uu, ff, s=s, alpha=alpha):
            c = limiting_curve(p, s, uu)
            return hy.limiting_slope(p, s, uu) + s * alpha * (c - ff)

        sol = solve_ivp(rate, (u[i0], u[i1]), [fcur], t_eval=u[i0:i1 + 1], rtol=1e-11, atol=1e-12 * (1 + abs(fcur)),
                        method="DOP853")
        f_ode.extend(sol.y[0, 1:])
        fcur = sol.y[0, -1]
    f_ode = np.array(f_ode)
    scale = np.max(np.abs(f))
    np.testing.assert_allclose(f, f_ode, atol=1e-8 * scale)


@pytest.mark.parametrize("name", sorted(SETS))
def test_tangent_matches_finite_differences(name):
    p = pset(SETS[name])
    amp = AMPLITUDE.get(name, 1.5)
    h = amp * 1e-6
    # along a branch that starts at a reversal at u = amp
    u = np.concatenate([np.linspace(0, amp, 200), amp - h * np.arange(1, 5000)])
    f, k, _ = loop(p, u)
    i = np.arange(205, 4990, 97)
    fd = (f[i - 1] - f[i + 1]) / (2 * h)  # u decreases along the branch
    np.testing.assert_allclose(k[i], fd, rtol=1e-5, atol=1e-7 * np.max(np.abs(k)))


@pytest.mark.parametrize("name", sorted(SETS))
def test_work_is_the_integral_of_force(name):
    p = pset(SETS[name])
    amp = AMPLITUDE.get(name, 1.5)
    _, u = sine_history(amp, cycles=2, n=20000)
    f, _, w = loop(p, u)
    trap = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(u))])
    np.testing.assert_allclose(w, trap, atol=1e-6 * np.max(np.abs(f)) * amp)


@pytest.mark.parametrize("name", sorted(TABLE1))
def test_table1_loops_reach_the_limiting_curves(name):
    """A full swing of 3 is 30/alpha: the force sits on c+(1.5) and c-(-1.5) to e^-30."""
    p = pset(TABLE1[name])
    _, u = sine_history()
    f, _, _ = loop(p, u)
    assert f.max() == pytest.approx(limiting_curve(p, 1, 1.5), abs=1e-9)
    assert f.min() == pytest.approx(limiting_curve(p, -1, -1.5), abs=1e-9)


def test_table1_shapes():
    # (a) asymmetric: the upper curve 0.5 u + 2 and the lower -2 give extremes 2.75 and -2
    f, _, _ = loop(pset(TABLE1["2a"]), sine_history()[1])
    assert (f.max(), f.min()) == pytest.approx((2.75, -2.0), abs=1e-9)
    # (b) pinched: the loop is thinner at u = 0 than at |u| = 1
    u = sine_history()[1]
    f, _, _ = loop(pset(TABLE1["2b"]), u)

    def width(at):
        second = slice(8000, 12001)
        uu, ff = u[second], f[second]
        up = np.diff(uu, append=uu[-1]) > 0
        return np.interp(at, *_sorted(uu[up], ff[up])) - np.interp(at, *_sorted(uu[~up], ff[~up]))

    assert width(0.0) < 0.6 * width(1.0)
    # (c) S-shaped: the limiting curves are steeper at 0 than at the ends: kb + g1 g2 = 4.5
    p = pset(TABLE1["2c"])
    assert hy.limiting_slope(p, 1, 0.0) == pytest.approx(4.5)
    assert hy.limiting_slope(p, 1, 1.5) == pytest.approx(0.5 + 4.0 / np.cosh(1.5) ** 2)
    assert hy.limiting_slope(p, 1, 1.5) < hy.limiting_slope(p, 1, 0.0) / 3
    # (d) flag-shaped: the curves jump by 0.5 * 0.2 + 2 * 2 g1 tanh(g2 * 0.1 / 2) within |u| < 0.1
    p = pset(TABLE1["2d"])
    jump = limiting_curve(p, 1, 0.1) - limiting_curve(p, 1, -0.1)
    assert jump == pytest.approx(0.1 + 8 * np.tanh(2.0), rel=1e-12)
    assert jump > 0.95 * 4 * 2.0  # nearly the full 4 g1 of the logistic term


def _sorted(x, y):
    o = np.argsort(x)
    return x[o], y[o]


@pytest.mark.parametrize("name", sorted(SETS))
def test_loop_closes_and_dissipates_its_area(name):
    p = pset(SETS[name])
    amp = AMPLITUDE.get(name, 1.5)
    n = 20000
    t, u = sine_history(amp, cycles=3, n=n)
    f, _, w = loop(p, u)
    c2, c3 = slice(n, 2 * n + 1), slice(2 * n, 3 * n + 1)
    # the stabilized loop repeats itself
    np.testing.assert_allclose(f[c2], f[c3], atol=1e-9 * np.max(np.abs(f)))
    # dissipated energy per cycle = the loop's area (shoelace), and it is positive
    area = 0.5 * abs(np.sum(u[c3][:-1] * f[c3][1:] - u[c3][1:] * f[c3][:-1]))
    dissipated = w[3 * n] - w[2 * n]
    assert dissipated > 0
    assert dissipated == pytest.approx(area, rel=1e-3)


def test_compiled_and_python_kernels_agree():
    p = pset(TABLE1["2b"]).reshape(1, 2, 8)
    state = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for u1 in (0.3, 0.7, 0.2, -0.4, -0.1):
        fast = vrm.vrm_update(p, 0, *state, u1)
        slow = vrm.vrm_update.py_func(p, 0, *state, u1)
        assert fast == pytest.approx(slow, rel=1e-14, abs=1e-15)
        f, s, g, k, a, _, _, _ = fast
        state = (u1, f, s, g, k, a)


def test_overflow_is_reported_not_returned():
    p = pset(TABLE3_AXIAL)
    with pytest.raises(OverflowError, match="calibrated"):
        loop(p, np.linspace(0, 4.0, 100))  # beta2 u = 920 > 700
