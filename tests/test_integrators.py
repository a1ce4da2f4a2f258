"""The fixed-step integrators: observed order against the reference, and each method's own traits.

The order is fitted, as ``rbhyst study`` does, over a half-octave ladder of 11 steps (a
factor 32): a fixed-step method meets a reversal somewhere inside a step and misses the
element's excursion beyond it, an O(dt^2) force error whose constant depends on where in
the step the reversal falls. Single halvings of dt scatter by a factor of several around
dt^2; a least-squares slope over 11 points does not.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from rbhyst.solve import integrators
from rbhyst.cli import app
from rbhyst.model.deck import parse_deck
from rbhyst.errors import AnalysisError
from rbhyst.solve.integrators import kr_alpha
from rbhyst.model.system import assemble
from rbhyst.solve.plan import Settings, simulate
from rbhyst.analyses.study import run_study
from conftest import records_or_skip, seed_deck, square_linear_deck, write_deck

SECOND_ORDER = ["chang", "central-difference", "newmark", "kr-alpha"]
K, MASS = 2.0e5, 500.0


def ladder(h0: float, n: int = 11) -> list[float]:
    return [h0 * 2.0 ** (-k / 2) for k in range(n)]


def el_centro_deck(duration: float) -> dict:
    """The seed's body and wire rope isolators under both horizontal components of El Centro 1940."""
    rec = records_or_skip()
    deck = seed_deck(duration=duration)
    deck["excitation"] = {"support": {"x1": {"file": str(rec / "I-ELC180.AT2"), "units": "g"},
                                      "x2": {"file": str(rec / "I-ELC270.AT2"), "units": "g"}}}
    return deck


@pytest.fixture(scope="module")
def smooth_study(tmp_path_factory):
    """The seed scene under bidirectional sine support motion (it starts at its peak in x1)."""
    system = assemble(parse_deck(seed_deck(duration=2.0)), tmp_path_factory.mktemp("smooth"))
    return run_study(system, Settings(dt=5e-4, duration=2.0), SECOND_ORDER, ladder(5e-4), repeat=1)


@pytest.fixture(scope="module")
def record_study(tmp_path_factory):
    """3 s of El Centro: the onset of the strong motion, hundreds of reversals."""
    deck = el_centro_deck(3.0)
    system = assemble(parse_deck(deck), tmp_path_factory.mktemp("record"))
    return run_study(system, Settings(dt=2.5e-4, duration=3.0), SECOND_ORDER, ladder(2.5e-4), repeat=1)


@pytest.mark.parametrize("method", SECOND_ORDER)
def test_observed_order_on_a_smooth_scene(smooth_study, method):
    order = smooth_study.orders[method]
    assert len(order["fit_dt_s"]) >= 9, order  # the fit really spans the ladder
    assert order["order"] == pytest.approx(2.0, abs=0.3)


@pytest.mark.parametrize("method", SECOND_ORDER)
def test_observed_order_under_a_real_record(record_study, method):
    order = record_study.orders[method]
    assert len(order["fit_dt_s"]) >= 9, order
    assert order["order"] == pytest.approx(2.0, abs=0.3)


@pytest.mark.parametrize("method", SECOND_ORDER)
def test_fixed_step_methods_converge_to_the_reference(record_study, method):
    runs = sorted((r for r in record_study.runs if r.integrator == method), key=lambda r: r.dt)
    assert all(r.failed is None for r in runs)
    finest, coarsest = runs[0], runs[-1]
    assert finest.err_max < 1e-3
    assert finest.err_max < coarsest.err_max / 100  # a factor 32 in dt: ~1000 for order 2


# ---------------------------------------------------------------- newmark


def linear_scene(tmp_path, phase_deg=90.0, cycles=None):
    deck = square_linear_deck(K, MASS)
    x1 = {"type": "sine", "amplitude": 2.0, "frequency_hz": 2.5, "units": "m/s2", "phase_deg": phase_deg}
    if cycles is not None:
        x1["cycles"] = cycles
    deck["excitation"] = {"support": {"x1": x1}}
    return assemble(parse_deck(deck), tmp_path)


def test_newmark_first_step_by_hand(tmp_path):
    """Average acceleration on the decoupled x1 mode: d1 = dt^2/4 (a0 + p1/m) / (1 + (w dt)^2 / 4)."""
    system = linear_scene(tmp_path)
    dt = 1e-2
    w2 = 2 * K / MASS
    res = simulate(system, Settings(integrator="newmark", dt=dt, duration=dt))
    a0, p1 = -2.0, -2.0 * math.cos(2 * math.pi * 2.5 * dt)
    d1 = 0.25 * dt * dt * (a0 + p1) / (1 + 0.25 * w2 * dt * dt)
    assert res.d[1, 0] == pytest.approx(d1, rel=1e-9)
    assert res.v[1, 0] == pytest.approx(0.5 * dt * (a0 + res.a[1, 0]), rel=1e-9)


def test_newmark_conserves_the_energy_of_a_linear_scene(tmp_path):
    """Average acceleration is energy conserving on linear systems: the balance closes to round-off."""
    system = linear_scene(tmp_path)
    res = simulate(system, Settings(integrator="newmark", dt=2e-3, duration=2.0))
    assert res.energy_balance < 1e-9


def test_newmark_retries_a_step_whose_iterations_fail(tmp_path):
    """Two iterations are too few for the seed scene at dt = 1 ms: substeps rescue the run."""
    system = assemble(parse_deck(seed_deck(duration=0.5)), tmp_path)
    normal = simulate(system, Settings(integrator="newmark", dt=1e-3, duration=0.5))
    assert normal.substeps == 0
    tight = simulate(system, Settings(integrator="newmark", dt=1e-3, duration=0.5, newton_max_iter=2))
    assert tight.substeps > 0
    # the substepped run is a finer Newmark run: close to the normal one
    diff = np.max(np.abs(tight.d - normal.d), axis=0) / np.max(np.abs(normal.d), axis=0)
    assert np.all(diff < 0.05)


def test_newmark_stops_with_a_clear_message_when_substeps_do_not_help(tmp_path):
    system = assemble(parse_deck(seed_deck(duration=0.1)), tmp_path)
    with pytest.raises(AnalysisError, match=r"Newton iterations of 'newmark' did not converge .* 4 substeps"):
        simulate(system, Settings(integrator="newmark", dt=1e-3, duration=0.1, newton_max_iter=1,
                                  max_substep_level=2))


# ---------------------------------------------------------------- kr-alpha


def test_kr_alpha_runs_the_published_recursion(tmp_path):
    """On the decoupled x1 mode the loop reproduces Kolay and Ricles' recursion step by step,
    started at v0 - gamma dt a0 (its velocity variable lags by gamma dt a, see kr_alpha.py)."""
    system = linear_scene(tmp_path)
    dt = 1e-2
    n = 50
    res = simulate(system, Settings(integrator="kr-alpha", dt=dt, duration=n * dt))
    am, af, gamma, beta = kr_alpha.parameters(kr_alpha.RHO_INF)
    k, m = 2 * K, MASS
    big_a = m + beta * dt * dt * k
    a1, a3 = m / big_a, (am * m + af * beta * dt * dt * k) / big_a
    a2 = (0.5 + gamma) * a1
    p = lambda t: -m * 2.0 * math.cos(2 * math.pi * 2.5 * t)  # noqa: E731
    d, a = 0.0, p(0.0) / m
    v = -gamma * dt * a
    for j in range(n):
        d1 = d + dt * v + dt * dt * a2 * a
        v = v + dt * a1 * a
        rhs = (1 - af) * (p((j + 1) * dt) - k * d1) + af * (p(j * dt) - k * d) - m * a3 * a
        a = rhs / (m * (1 - a3))
        d = d1
        assert res.d[j + 1, 0] == pytest.approx(d, rel=1e-10, abs=1e-15)
    # its velocity at t is the lagging variable put forward: v + gamma dt a
    assert res.v[n, 0] == pytest.approx(v + gamma * dt * a, rel=1e-9)


@pytest.mark.parametrize("rho", [0.0, 0.5, 1.0])
def test_kr_alpha_spectral_radius_at_infinity_is_rho_inf(rho):
    """The linear amplification matrix of the published recursion (K = K0, one mode, w dt = 1e4)."""
    wdt = 1e4
    am, af, gamma, beta = kr_alpha.parameters(rho)
    big_a = 1 + beta * wdt**2
    a1, a3 = 1 / big_a, (am + af * beta * wdt**2) / big_a
    a2 = (0.5 + gamma) * a1
    # state (d, v dt, a dt^2): one step with dt = 1 and w^2 = wdt^2
    amp = np.zeros((3, 3))
    for col in range(3):
        d, v, a = np.eye(3)[col]
        d1 = d + v + a2 * a
        v1 = v + a1 * a
        a_1 = (-(1 - af) * wdt**2 * d1 - af * wdt**2 * d - a3 * a) / (1 - a3)
        amp[:, col] = (d1, v1, a_1)
    assert max(abs(np.linalg.eigvals(amp))) == pytest.approx(rho, abs=5e-3)


def test_kr_alpha_damps_a_mode_it_cannot_resolve(tmp_path):
    """w dt = 2 after one cycle of forcing: kr-alpha (rho_inf 0.5) damps the free vibration,
    chang and newmark keep its amplitude. (The forcing's steps are split to follow the sine,
    to 0.5 s: the free vibration is compared after them, all at w dt = 2.)"""
    system = linear_scene(tmp_path, phase_deg=0.0, cycles=1.0)
    w = math.sqrt(2 * K / MASS)
    dt = 2.0 / w
    kept = {}
    for name in ("chang", "newmark", "kr-alpha"):
        res = simulate(system, Settings(integrator=name, dt=dt, duration=6.0, max_omega_dt=10.0))
        free = res.time > 0.6
        half = len(res.time[free]) // 2
        u = res.d[free, 0]
        kept[name] = np.max(np.abs(u[half:])) / np.max(np.abs(u[:half]))
    assert kept["chang"] > 0.95
    assert kept["newmark"] > 0.95
    assert kept["kr-alpha"] < 0.2


def test_kr_alpha_reports_equilibrium_acceleration(tmp_path):
    system = linear_scene(tmp_path)
    res = simulate(system, Settings(integrator="kr-alpha", dt=1e-3, duration=0.2))
    p = -2.0 * np.cos(2 * math.pi * 2.5 * res.time)
    assert np.max(np.abs(res.a[:, 0] - (p - 2 * K / MASS * res.d[:, 0]))) < 1e-9


# ---------------------------------------------------------------- every method


def test_every_method_documents_order_stability_and_dissipation():
    import importlib

    for name in integrators.names():
        method = integrators.get(name)
        module = importlib.import_module(f"rbhyst.solve.integrators.{name.replace('-', '_')}")
        doc = (module.__doc__ or "").lower()
        assert "order" in doc and "stab" in doc or method.solve is not None, name
        assert "dissipat" in doc or method.solve is not None or name == "central-difference", name


@pytest.mark.parametrize("name", integrators.names())
def test_every_integrator_runs_from_the_command_line(tmp_path, name):
    deck = seed_deck(duration=0.2)
    path = write_deck(tmp_path, deck)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--integrator", name, "--out", str(out), "--no-plots"])
    assert res.exit_code == 0, res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["analysis"]["integrator"] == name
    assert summary["energy"]["balance_error"] < 0.01
    table = np.loadtxt(out / "time_history.csv", delimiter=",", skiprows=1)
    assert table.shape[0] == 201 and np.all(np.isfinite(table))


def test_the_deck_accepts_every_integrator(tmp_path):
    for name in integrators.names():
        deck = copy.deepcopy(seed_deck(duration=0.05))
        deck["analysis"]["integrator"] = name
        assert parse_deck(deck).analysis.integrator == name


@pytest.mark.parametrize("name", ["chang", "central-difference", "newmark", "kr-alpha"])
def test_coefficients_for_every_substep_level_at_once_are_those_of_each(name):
    """A plan takes the coefficients of all its substep levels in one call: bit for bit those
    of each level alone (with damping, a stiff K0, steps from 1 ms to 1 ms / 2^12)."""
    rng = np.random.default_rng(3)
    mass = rng.uniform(1.0, 1000.0, 3)
    k0 = rng.normal(size=(3, 3))
    k0 = 1e5 * k0 @ k0.T
    c = 10.0 * rng.normal(size=(3, 3)) ** 2
    steps = 1e-3 / 2.0 ** np.arange(13)
    method = integrators.get(name)
    each = np.stack([method.coefficients(mass, k0, c, h) for h in steps])
    assert np.array_equal(method.coefficients(mass, k0, c, steps), each)
