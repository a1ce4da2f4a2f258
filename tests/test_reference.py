"""The reference solution: exact linear solutions, eq. 14 along its branches, its tolerance, its speed."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from rbhyst.model.deck import load_deck, parse_deck
from rbhyst.model.vrm import loop
from rbhyst.solve.integrators import reference
from rbhyst.model.system import assemble
from rbhyst.model.records import Series
from rbhyst.solve.plan import Settings, settings_from_deck
from conftest import DECKS, SEED_MASS, SEED_VERTICES, linear_set, seed_deck, write_deck

K = 2.0e5
SUPPORT = {  # (amplitude m/s2, Hz, phase deg) along x1 and x2
    "x1": (2.0, 2.5, 90.0),
    "x2": (1.5, 4.0, 30.0),
}


def coupled_linear_deck(start: float = 0.0, cycles: float | None = None) -> dict:
    """The seed's L-shaped body on linear springs: off-centre, so translations and rotation couple."""
    support = {}
    for axis, (amp, f, ph) in SUPPORT.items():
        sig = {"type": "sine", "amplitude": amp, "frequency_hz": f, "units": "m/s2", "phase_deg": ph,
               "start": start}
        if cycles is not None:
            sig["cycles"] = cycles
        support[axis] = sig
    return {
        "body": {"vertices": SEED_VERTICES, "mass": SEED_MASS},
        "hysteresis": {"lin": linear_set(K), "stiff": linear_set(3 * K)},
        "elements": [
            {"vertex": 1, "angle_deg": 0.0, "hysteresis": "lin"},
            {"vertex": 1, "angle_deg": 90.0, "hysteresis": "stiff"},
            {"vertex": 2, "angle_deg": 0.0, "hysteresis": "stiff"},
            {"vertex": 5, "angle_deg": 90.0, "hysteresis": "lin"},
            {"vertex": 7, "angle_deg": 30.0, "hysteresis": "lin"},
        ],
        "excitation": {"support": support},
        "analysis": {"dt": 1e-3, "duration": 2.0},
    }


def exact_linear(system, t, start=0.0, cycles=None):
    """Modal solution of M q'' + K q = -M (ag1, ag2, 0) from rest, each support component
    A sin(W (t - t0) + phi) on [t0, t0 + cycles / f], free vibration after it."""
    m = system.mass
    kmat = (system.bvec.T * (system.mult * system.k0)) @ system.bvec
    mi = 1.0 / np.sqrt(m)
    lam, psi = np.linalg.eigh(kmat * np.outer(mi, mi))
    phi = psi * mi[:, None]  # M-orthonormal mode shapes
    w = np.sqrt(lam)
    q = np.zeros((len(t), 3))
    for axis, (amp, f, ph) in SUPPORT.items():
        r = np.zeros(3)
        r[0 if axis == "x1" else 1] = 1.0
        big_w, ph = 2 * math.pi * f, math.radians(ph)
        t1 = math.inf if cycles is None else start + cycles / f
        for j in range(3):
            pj = -(phi[:, j] @ (m * r)) * amp  # modal load amplitude
            wj = w[j]
            c = pj / (wj * wj - big_w * big_w)

            def eta(tau):  # response to pj sin(W tau + ph) from rest
                return c * (np.sin(big_w * tau + ph) - math.sin(ph) * np.cos(wj * tau)
                            - big_w / wj * math.cos(ph) * np.sin(wj * tau))

            def deta(tau):
                return c * big_w * (np.cos(big_w * tau + ph) + wj / big_w * math.sin(ph) * np.sin(wj * tau)
                                    - math.cos(ph) * np.cos(wj * tau))

            tau = t - start
            during = (tau >= 0) & (t <= t1)
            y = np.where(during, eta(np.maximum(tau, 0.0)), 0.0)
            if math.isfinite(t1):
                e1, v1 = eta(t1 - start), deta(t1 - start)
                after = t > t1
                s = t[after] - t1
                y[after] = e1 * np.cos(wj * s) + v1 / wj * np.sin(wj * s)
            q += np.outer(y, phi[:, j])
    return q


def rel_errors(d, exact):
    return np.max(np.abs(d - exact), axis=0) / np.max(np.abs(exact), axis=0)


def test_reference_matches_an_exact_coupled_linear_solution(tmp_path):
    """Equal branches with f0 = 0 are linear springs: the reference agrees with the modal solution to 1e-8."""
    system = assemble(parse_deck(coupled_linear_deck()), tmp_path)
    res, stats = reference.solve_with_stats(system, Settings(integrator="reference", dt=1e-3, duration=2.0))
    exact = exact_linear(system, res.time)
    assert np.min(np.max(np.abs(exact), axis=0)) > 1e-5  # every coordinate really moves
    assert np.all(rel_errors(res.d, exact) < 1e-8), rel_errors(res.d, exact)
    assert stats["reversals"] > 10  # events fire (and change nothing for a linear spring)


def test_reference_handles_a_load_that_jumps_on_and_off(tmp_path):
    """Sines from t0 = 0.1 s with a 60-degree phase for 3 cycles: the load jumps at both ends."""
    deck = coupled_linear_deck(start=0.1, cycles=3.0)
    system = assemble(parse_deck(deck), tmp_path)
    res = reference.solve(system, Settings(integrator="reference", dt=1e-3, duration=2.0))
    exact = exact_linear(system, res.time, start=0.1, cycles=3.0)
    assert np.all(rel_errors(res.d, exact) < 1e-8), rel_errors(res.d, exact)


def test_load_pieces_follow_records_and_signals_exactly_and_find_kinks(tmp_path):
    system = assemble(parse_deck(coupled_linear_deck(start=0.1, cycles=3.0)), tmp_path)
    pieces = reference.load_pieces(system, 2.0)
    # a breakpoint within 1e-9 s of the start and of each sine's end (3/2.5 and 3/4 s after it)
    for t in (0.1, 0.1 + 3 / 2.5, 0.1 + 3 / 4.0):
        assert np.min(np.abs(pieces.brk - t)) < 1e-9, t
    # the analytic signals are evaluated, not fitted: the load everywhere but at its jumps, exactly
    t = np.linspace(0.0, 2.0, 4001)
    t = t[np.min(np.abs(t[:, None] - pieces.brk[None, :]), axis=1) > 1e-9]
    np.testing.assert_array_equal(pieces.at(t), system.excitation.load(t, system.mass))
    # a record: linear between its samples, so its samples are breakpoints and linear pieces are exact
    rec = tmp_path / "rec.csv"
    rng = np.random.default_rng(1)
    np.savetxt(rec, np.column_stack([0.01 * np.arange(101), rng.normal(size=101)]), delimiter=",",
               header="t,a", comments="")
    deck = coupled_linear_deck()
    deck["excitation"] = {"support": {"x1": {"file": str(rec), "units": "m/s2"}}}
    system = assemble(parse_deck(deck), tmp_path)
    pieces = reference.load_pieces(system, 1.0)
    assert np.all(np.isin(np.round(0.01 * np.arange(101), 9), np.round(pieces.brk, 9)))
    t = np.linspace(0.0, 1.0, 3001)
    exact = system.excitation.load(t, system.mass)
    assert np.max(np.abs(pieces.at(t) - exact)) < 1e-12 * np.max(np.abs(exact))
    assert isinstance(system.excitation.ag1, Series)
    assert pieces.ends.shape == (len(pieces.brk) - 1, 2, 3)  # two numbers a piece: memory of the record's size


def test_a_fast_long_sine_costs_no_memory_per_step(tmp_path):
    """A 113 Hz force for 13.5 s: no piece per period, no table per step (it once took 31 million
    samples of load and gigabytes)."""
    deck = coupled_linear_deck()
    deck["excitation"] = {"force": {"p1": {"type": "sine", "amplitude": 80.0, "frequency_hz": 113.181,
                                            "units": "N"}}}
    system = assemble(parse_deck(deck), tmp_path)
    pieces = reference.load_pieces(system, 13.5)
    assert len(pieces.brk) == 2 and pieces.analytic.shape == (1, 11)


@pytest.fixture(scope="module")
def hysteretic(tmp_path_factory):
    system = assemble(parse_deck(seed_deck(duration=2.0)), tmp_path_factory.mktemp("seed"))
    return system, reference.solve_with_stats(system, Settings(integrator="reference", dt=1e-4, duration=2.0))


def test_reference_forces_follow_eq14_along_its_own_path(hysteretic):
    """Driving each element's VRM (hysteresis.loop) along the reference's displacement history gives
    the reference's forces: the reversals it located are where the element turns back."""
    system, (res, stats) = hysteretic
    assert stats["reversals"] > 10
    k = 0
    for el in system.elements:
        f, _, _ = loop(system.params[el.row], res.element_u[:, k])
        scale = np.max(np.abs(res.element_f[:, k]))
        assert np.max(np.abs(f - res.element_f[:, k])) < 2e-4 * scale, el
        k += el.count


def test_reference_energy_balance_closes(hysteretic):
    _, (res, _) = hysteretic
    assert res.energy_balance < 1e-9
    assert res.energy[-1, 2] > 0.5 * res.energy[-1, 0]  # the isolators dissipate most of the input


def test_reference_converges_with_its_tolerance(hysteretic):
    system, (tight, _) = hysteretic
    loose = reference.solve_with_stats(system, tight.settings, rtol=1e-9)[0]
    diff = rel_errors(loose.d, tight.d)
    assert np.all(diff < 1e-5), diff
    assert np.max(diff) > 1e-12  # the tolerance does something


def test_reference_fills_every_column_on_the_settings_grid(hysteretic):
    system, (res, _) = hysteretic
    table = res.table
    assert np.all(np.isfinite(table))
    assert np.allclose(res.time, 1e-4 * np.arange(20001), rtol=0, atol=1e-12)
    assert res.element_u.shape == (20001, system.n_output_elements)
    # accelerations are equilibrium at the reference's state
    first = [system.row_elements(row)[0] - 1 for row in range(len(system.mult))]  # a CSV column per row
    r = (system.bvec.T @ (system.mult[:, None] * res.element_f[:, first].T)).T
    p = system.excitation.load(res.time, system.mass)
    assert np.max(np.abs(res.a - (p - r) / system.mass)) < 1e-9 * np.max(np.abs(res.a))


def test_reference_is_fast_enough_on_the_seed_deck():
    """The seed deck's 40 s record: well within the tens of seconds a study can spend on its reference."""
    deck = load_deck(DECKS / "seed_wri.toml")
    system = assemble(deck, DECKS)
    start = time.perf_counter()
    res, stats = reference.solve_with_stats(system, settings_from_deck(deck))
    total = time.perf_counter() - start
    assert stats["wall_s"] < 30.0 and total < 60.0
    assert res.energy_balance < 1e-9
    assert stats["reversals"] > 1000


def test_reference_on_a_deck_from_the_command_line(tmp_path):
    from typer.testing import CliRunner

    from rbhyst.cli import app

    deck = seed_deck(duration=0.5)
    deck["analysis"]["integrator"] = "reference"
    path = write_deck(tmp_path, deck)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out"), "--no-plots"])
    assert res.exit_code == 0, res.stderr
    assert "reference, dt = 0.001 s" in res.stderr
