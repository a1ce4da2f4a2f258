"""The error estimate from a run's companion (rbhyst.solve.companion): each method's modified
equation, the re-driven forces, and where the adaptive solutions take over."""

from __future__ import annotations

import numpy as np
import pytest

import rbhyst
from conftest import DECKS, seed_deck, square_linear_deck, write_deck
from test_accuracy import true_errors

METHODS = ["chang", "central-difference", "newmark"]


def ratios(res) -> dict[str, float]:
    """Every column's estimate over its true error (against the adaptive solution at rtol 1e-12)."""
    est = res.accuracy["estimated_error"]
    return {k: est[k] / t for k, t in true_errors(res).items() if t > 1e-9}


def sine_on_square(damping: dict | None = None) -> dict:
    """The square on four linear springs (2.0 Hz in translation) shaken at 1.3 Hz along x1 and
    0.7 Hz along x2: nothing yields, so the run's error is the method's alone."""
    data = square_linear_deck(k=4.0e4, mass=500.0)
    data["excitation"] = {"support": {
        "x1": {"type": "sine", "amplitude": 0.2, "frequency_hz": 1.3, "units": "g", "phase_deg": 90.0},
        "x2": {"type": "sine", "amplitude": 0.1, "frequency_hz": 0.7, "units": "g"}}}
    data["analysis"] = {"dt": 0.004, "duration": 4.0, "warn_error": 0.2}
    if damping is not None:
        data["damping"] = damping
    return data


def reference_terms(method, a, v, t, h, mass, c, k0):
    """(-S, q' - V) written out with numpy from rbhyst.solve.companion's formulas: what the
    compiled pass (rbhyst.solve.kernels.modified) must give."""
    d1, d2 = np.zeros_like(a), np.zeros_like(a)
    if len(a) >= 3:
        hl, hr = np.diff(t)[:-1, None], np.diff(t)[1:, None]
        sl, sr = (a[1:-1] - a[:-2]) / hl, (a[2:] - a[1:-1]) / hr
        d2[1:-1] = 2.0 * (sr - sl) / (hl + hr)
        d1[1:-1] = (hl * sr + hr * sl) / (hl + hr)
        d1[0] = (-1.5 * a[0] + 2.0 * a[1] - 0.5 * a[2]) / (t[1] - t[0])
        d1[-1] = (1.5 * a[-1] - 2.0 * a[-2] + 0.5 * a[-3]) / (t[-1] - t[-2])
    hh = (h * h)[:, None]
    cd1 = d1 @ c.T if c is not None else 0.0
    if method == "newmark":
        return -hh * (d2 * mass / 6.0 + cd1 / 12.0), hh * d1 / 12.0
    if method == "central-difference":
        return hh * (d2 * mass / 12.0 + cd1 / 6.0), -hh * d1 / 6.0
    w = (v @ k0.T + (a @ c.T if c is not None else 0.0)) / mass
    extra = hh * (d2 * mass / 12.0 + 0.25 * (a @ k0.T) + ((5.0 / 12.0) * cd1 + 0.25 * (w @ c.T) if c is not None else 0.0))
    return extra, -hh * (d1 / 6.0 + 0.25 * w)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("damped", [False, True])
def test_the_compiled_modified_equation_is_the_formulas(method, damped):
    """The companion's load and starting velocity from the compiled pass against the formulas
    written out with numpy, on an uneven grid, with nodes near a signal's corner left without
    source; two and three nodes (no second difference, one) as well."""
    from rbhyst.solve.companion import source_and_offset

    rng = np.random.default_rng(7)
    for nodes in (2, 3, 40):
        a, v = rng.normal(size=(nodes, 3)), rng.normal(size=(nodes, 3))
        t, h = np.cumsum(rng.uniform(0.5, 1.5, nodes)), rng.uniform(0.5, 1.5, nodes)
        mass, k0 = rng.uniform(1.0, 2.0, 3), rng.normal(size=(3, 3))
        c = rng.normal(size=(3, 3)) if damped else None
        near = rng.random(nodes) < 0.2
        extra, offset = source_and_offset(method, a, v, t, h, mass, c, k0 @ k0.T, near)
        want_extra, want_offset = reference_terms(method, a, v, t, h, mass, c, k0 @ k0.T)
        want_extra[near] = 0.0
        assert np.allclose(extra, want_extra, rtol=1e-13, atol=1e-13 * np.abs(want_extra).max())
        assert np.allclose(offset, want_offset, rtol=1e-13, atol=1e-13 * np.abs(want_offset).max())


@pytest.mark.parametrize("method", METHODS)
def test_the_companion_s_source_from_the_run_s_rows_is_the_formulas(tmp_path, method):
    """companion.source_from_run (one compiled pass from the tap's rows) against the pieces written
    out with numpy: the method's accelerations M^-1 (p - R - C V), each step h = dt / nsub / 2^level
    from the steps the monitor split, no source within 1.5 h of the shock's start and end, then
    source_and_offset (the same to rounding: numpy's products sum in another order). A 20 g shock a third of dt long (14 substeps a step around it) on the
    seed's body with Rayleigh damping, coarse enough (dt = 4 ms) that the monitor splits steps."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.choose import companion_of as _companion
    from rbhyst.solve.companion import source_and_offset, source_from_run
    from rbhyst.solve.plan import compute_times

    data = seed_deck(duration=0.4, dt=4e-3)
    data["excitation"] = {"support": {"x1": {"type": "half-sine", "amplitude": 20.0, "units": "g",
                                             "duration": 0.0013, "start": 0.0507}}}
    data["damping"] = {"rayleigh": {"ratio": 0.05, "modes": [1, 3]}}
    data["analysis"]["integrator"] = method
    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, data)))
    planned, tap = _companion(plan(system, settings))
    planned.run(keep=False, tap=tap)
    assert planned.substeps.max() > 1 and tap.levels.any() and tap.c is not None
    n, s = system.n, settings
    a = np.empty((len(tap.t), n))
    a[0] = tap.a0
    a[1:] = (tap.load[1:, :n] - tap.f[1:] @ planned.rb - tap.v[1:] @ tap.c.T) / system.mass
    lengths = np.diff(planned.bounds)
    h = np.append(np.repeat(s.dt / planned.substeps, lengths * planned.substeps) / 2.0**tap.levels, 0.0)
    h[-1] = h[-2]
    t = np.append(0.0, compute_times(planned.bounds, planned.substeps, s.dt))
    assert np.array_equal(t, tap.t)
    shock = system.excitation.signals["ag1"]
    near = np.any([np.abs(t - b) <= 1.5 * h for b in shock.breakpoints], axis=0)
    assert 0 < near.sum() < 20
    want = source_and_offset(method, a, tap.v, t, h, system.mass, tap.c, system.K0, near)
    got = source_from_run(planned, tap)
    for x, y in zip(got, want):
        assert np.allclose(x, y, rtol=0.0, atol=1e-12 * np.abs(y).max()), np.abs(x - y).max() / np.abs(y).max()
    assert np.all(got[0][near] == 0.0) and np.abs(got[0][~near]).max() > 0.0


@pytest.mark.parametrize("method", METHODS)
def test_each_method_s_modified_equation_gives_its_error_on_a_linear_body(tmp_path, method):
    """Where the response is smooth the companion is the exact solution to O(h^4): the estimate is
    the true error within a few per cent (a wrong coefficient of S, such as Newmark's h^2/6 for
    chang, is off by a factor of 5)."""
    res = rbhyst.run(write_deck(tmp_path, sine_on_square()), integrator=method)
    assert "companion" in res.accuracy and "reference" not in res.accuracy
    for key in ("u1", "u2", "at1", "at2", "R1", "R2", "e1_f", "e3_f"):
        assert 0.9 < ratios(res)[key] < 1.1, (key, ratios(res)[key])


@pytest.mark.parametrize("method", METHODS)
def test_viscous_damping_enters_the_modified_equation(tmp_path, method):
    """With Rayleigh damping (10 % at both modes) the C terms of S: every column within 10 %."""
    data = sine_on_square({"rayleigh": {"ratio": 0.1, "modes": [1, 3]}})
    res = rbhyst.run(write_deck(tmp_path, data), integrator=method)
    assert "companion" in res.accuracy
    r = ratios(res)
    assert all(0.9 < v < 1.1 for v in r.values()), r


@pytest.mark.parametrize("method", METHODS)
def test_the_seed_scene_s_estimate_is_honest_in_every_column(tmp_path, method):
    """Yield and reversals, turns within steps: the largest estimate within 20 % of the largest
    true error, every column within [0.5, 2] of its own (with the companion's turns on the nodes
    u1, far below alphat3, read 3.5 times its error)."""
    data = seed_deck(duration=2.0, warn_error=0.9, dt=5e-4)
    res = rbhyst.run(write_deck(tmp_path, data), integrator=method)
    assert "companion" in res.accuracy
    r = ratios(res)
    assert all(0.5 <= v <= 2.0 for v in r.values()), r
    worst = max(true_errors(res).values())
    assert 0.8 <= max(res.accuracy["estimated_error"].values()) / worst <= 1.25


def test_a_body_that_creeps_under_cyclic_load_is_estimated_in_every_column():
    """The machine on its inclined mounts creeps vertically under its unbalance (u2 and the top
    mount's force drift by what each reversal leaves). The run's turns at the nodes put an O(h^2)
    error into that drift; a companion whose turns also fall on the nodes shares it and cancels
    it (u2 and e3_f read 0.05 of their error); stepped with every turn located within its step
    (kernels.layout.LOCATED) it does not: every column within 10 %."""
    deck = rbhyst.load_deck(DECKS / "machine_on_mounts.toml").with_values({"analysis.kinematics": "small"})
    res = rbhyst.run(deck)
    assert "companion" in res.accuracy
    r = ratios(res)
    assert all(0.9 <= v <= 1.1 for v in r.values()), r


def test_forces_re_driven_with_the_reversal_located(tmp_path):
    """The redrive kernel: an element driven along samples of a smooth turn reaches the force of
    the turn driven exactly (the vertex inserted), where the plain samples miss it by O(h^2)."""
    from rbhyst.model.hysteresis import parameter_set
    from rbhyst.model.vrm import drive
    from rbhyst.solve.kernels.compiled import kernel
    from conftest import TABLE3_SHEAR

    p = np.ascontiguousarray(parameter_set(TABLE3_SHEAR["loading"], TABLE3_SHEAR["unloading"])[None])
    t = np.linspace(0.0, 1.0, 41)
    u = 0.02 * np.sin(2 * np.pi * 0.8 * t + 0.3)  # turns once, between samples
    fine_t = np.linspace(0.0, 1.0, 40_001)
    fine = np.empty(len(fine_t)), np.empty(len(fine_t)), np.empty(len(fine_t))
    drive(p[0], 0.02 * np.sin(2 * np.pi * 0.8 * fine_t + 0.3), *fine)
    exact = fine[0][::1000]
    located = np.empty((len(t), 1))
    assert kernel("redrive")(p, np.zeros((1, 6)), np.ascontiguousarray(u[:, None]), located) == -1
    plain = np.empty(len(t)), np.empty(len(t)), np.empty(len(t))
    drive(p[0], u, *plain)
    after = t > 0.5
    err_located = np.max(np.abs(located[after, 0] - exact[after]))
    err_plain = np.max(np.abs(plain[0][after] - exact[after]))
    assert err_located < 0.05 * err_plain, (err_located, err_plain)


@pytest.mark.parametrize("every", [1, 3, 7])
def test_the_probe_takes_the_compared_rows_of_every_chunk(tmp_path, every):
    """On a grid without substeps the probe finds each chunk's compared rows by arithmetic: with
    eps = 0 it is the run at every compared step, bit for bit, over chunks of 7 steps whose rows
    every 3rd or 7th step fall anywhere in them."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.choose import companion_of as _companion
    from rbhyst.solve.companion import Companion

    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, seed_deck(duration=0.5))))
    planned = plan(system, settings)
    run, tap = _companion(planned)
    run.run(keep=False, tap=tap)
    companion = Companion(planned, tap, every)
    assert isinstance(companion.take, slice)
    planned.fine_chunk = 7
    moved, _ = companion.probe(0.0)
    assert len(moved[0]) == len(range(0, len(tap.d), every))
    assert all(np.all(m == 0.0) for m in moved)


def test_the_probe_repeats_the_run_and_moves_a_determined_history_in_proportion(tmp_path):
    """The check near the warning is the run again with eps times the companion's source: with eps
    = 0 it is the run bit for bit at the compared steps (a shock that splits steps into substeps,
    every third step compared); a determined history moves in proportion to eps (twice as far for
    twice eps, within 2 %), by no more than eps times its error in any column (the source is the
    error's share from the method's formulas: the share from turns at the nodes, up to 0.6 of a
    force's error here, it does not move)."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.choose import companion_of as _companion
    from rbhyst.solve.companion import Companion

    data = seed_deck(duration=1.0, dt=2e-3)
    data["excitation"] = {"support": {"x1": {"type": "half-sine", "amplitude": 20.0, "units": "g",
                                             "duration": 0.0031, "start": 0.0507}}}
    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, data)))
    planned = plan(system, settings)
    assert planned.substeps.max() > 1
    run, tap = _companion(planned)
    res = run.run(keep=False, tap=tap)
    companion = Companion(planned, tap, 3)
    moved, _ = companion.probe(0.0)
    assert all(np.all(m == 0.0) for m in moved) and len(moved[0]) == len(res.compared[::3])
    diff, _ = companion.run()
    moved, _ = companion.probe(1e-3)
    change = res.layout.largest_change
    share = change(*moved) / (1e-3 * change(*diff))
    assert np.all(share < 1.1) and np.max(share) > 0.9, share
    twice = change(*companion.probe(2e-3)[0]) / change(*moved)
    assert np.all((1.98 < twice) & (twice < 2.02)), twice


def test_a_run_and_its_estimate_do_not_depend_on_where_its_chunks_start(tmp_path):
    """A shock a third of dt long splits the steps around it in 14 (the compute nodes at k/14
    of a step, not a binary fraction): the tapped run, its companion and its probe, in one chunk a segment or in
    chunks of 7 steps, give the same rows and estimate bit for bit (a node's time counts its
    thirds from t = 0, not from the chunk's start, and a chunk starts on the run's state)."""
    from rbhyst.results.analysis import analyse, plan, scene

    data = seed_deck(duration=0.4, dt=2e-3)
    data["excitation"] = {"support": {"x1": {"type": "half-sine", "amplitude": 20.0, "units": "g",
                                             "duration": 0.0061, "start": 0.0507}}}
    data["analysis"]["warn_error"] = 1e-4  # (the probe runs too)
    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, data)))
    results = []
    for chunk in (None, 7):
        planned = plan(system, settings)
        assert planned.substeps.max() == 14 and len(planned.bounds) > 2
        if chunk is not None:
            planned.fine_chunk = chunk
        results.append(analyse(system, settings, planned=planned))
    whole, small = results
    assert whole.accuracy["companion"]["probe"] > 0
    np.testing.assert_array_equal(whole.table, small.table)
    assert whole.accuracy["estimated_error"] == small.accuracy["estimated_error"]
    assert whole.accuracy["companion"]["spread"] == small.accuracy["companion"]["spread"]


@pytest.mark.parametrize("chunk", [None, 7])
def test_the_companion_reports_its_forces_with_every_turn_where_it_falls(chunk):
    """The companion's rows report each element's force with its turn where it falls, before the
    row or after it (kernels.loop, LOCATED: a row whose element turned before it is patched by
    the next step, across a chunk's start too): the forces of the elements driven along the
    companion's deformations with every vertex inserted (kernels.redrive, the pass the rows
    replace where no step is split), to rounding. Chunks of 7 steps put thousands of chunk
    starts in the seed deck; the rows a turn before them patches are some hundreds."""
    from rbhyst.results.analysis import plan as make_plan, scene
    from rbhyst.solve.companion import Companion, RunTap, KeptRows
    from rbhyst.solve.kernels.compiled import kernel
    from rbhyst.solve.kernels.layout import LOCATED, x_slice

    system, settings = scene(rbhyst.load_deck(DECKS / "seed_wri.toml"))
    plan = make_plan(system, settings)
    tap = RunTap(plan)
    run = plan.run(keep=False, tap=tap)
    companion = Companion(plan, tap, run.compare_every)
    if chunk is not None:
        plan.fine_chunk = chunk
    x, st = plan.initial_state()
    x[x_slice(system.n, 1)] = -companion.offset[0]
    st0 = st[0, :, :6].copy()
    rows = KeptRows(plan.start_row(x, st), len(companion.extra), keep=("u", "f"))
    load = companion.load.copy()
    load[:, :system.n] += companion.extra
    _, levels = plan.step_through(x, st, load, companion.levels, rows, rot=LOCATED)
    assert np.array_equal(levels, companion.levels)
    ref = np.empty_like(rows.u)
    assert not companion.levels.any()
    assert kernel("redrive")(plan.params, st0, np.ascontiguousarray(rows.u), ref) == -1
    scale = np.max(np.abs(ref))
    assert np.max(np.abs(rows.f - ref)) < 1e-10 * scale
    u = rows.u
    d0, d1 = u[1:-1] - u[:-2], u[2:] - u[1:-1]
    with np.errstate(invalid="ignore", divide="ignore"):
        before = (d0 * d1 < 0) & (0.5 * (u[:-2] - u[2:]) / (d1 - d0) < 0)  # the vertex before the row
    assert before.sum() > 100
    assert np.all(np.abs(rows.f[1:-1][before] - ref[1:-1][before]) < 1e-10 * scale)


def test_the_check_on_a_core_of_its_own_gives_the_same_estimate(monkeypatch):
    """With a spare core the probe steps on a thread of its own while the companion runs (both
    step the same plan: each chunk's end reported into its own array): the seed deck, which
    warns and is checked, gets the same estimate and the same spread to the bit either way; a
    sweep's worker, whose siblings take the other cores, starts no such thread, nor a run too
    short to pay for one."""
    from rbhyst.analyses.sweep import worker
    from rbhyst.results.analysis import analyse, scene
    from rbhyst.solve import beside as threads

    started = []

    class Counted(threads.Beside):
        def __init__(self, *args, name=""):
            if "check" in name:  # (the re-drive's second half is another thread)
                started.append(args)
            super().__init__(*args, name=name)

    monkeypatch.setattr(threads, "Beside", Counted)
    deck = rbhyst.load_deck(DECKS / "seed_wri.toml")
    system, settings = scene(deck, integrator="chang")  # (the seed's method at its dt: it warns)
    alone = analyse(system, settings, keep=False, spare_core=False).accuracy
    assert not started
    beside = analyse(system, settings, keep=False, spare_core=True).accuracy
    assert len(started) == 1
    assert "spread" in alone["companion"] and alone["estimated_error"]["R3"] > settings.warn_error
    assert beside["estimated_error"] == alone["estimated_error"]
    assert beside["companion"]["spread"] == alone["companion"]["spread"]
    worker.run_deck(deck, keep=False)
    assert len(started) == 1
    short = deck.with_values({"analysis.duration": 2.0})  # 16,000 element steps: a thread would cost more
    analyse(*scene(short), keep=False, spare_core=True)
    assert len(started) == 1


@pytest.mark.parametrize("method", METHODS)
def test_steps_the_stiffness_monitor_split_are_split_alike_in_the_companion(tmp_path, method):
    """A random scene of the tests whose stiffening elements make the monitor split 352 compute
    steps into substeps: the companion, given the run's levels, repeats the run bit for bit with
    no source (the probe at eps = 0), and its estimate is every column's true error within
    [0.75, 1.25] (the companion's source at the substeps' h: taken at the compute step's, the
    split steps' error would read 4 to 4^k times too large)."""
    from test_accuracy import random_scene

    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.choose import companion_of as _companion
    from rbhyst.solve.companion import Companion

    data = random_scene(np.random.default_rng(1021))
    data["analysis"]["kinematics"] = "small"  # (the companion's rows are the seed's)
    path = write_deck(tmp_path, data)
    res = rbhyst.run(path, integrator=method)
    assert res.stats.substeps > 0 and "companion" in res.accuracy
    r = ratios(res)
    assert all(0.75 <= v <= 1.25 for v in r.values()), r
    system, settings = scene(rbhyst.load_deck(path), integrator=method)
    planned = plan(system, settings)
    run, tap = _companion(planned)
    out = run.run(keep=False, tap=tap)
    moved, _ = Companion(planned, tap, out.compare_every).probe(0.0)
    assert all(np.all(m == 0.0) for m in moved)


@pytest.mark.parametrize("why", ["kr-alpha", "exact", "exact in space", "spectra", "near the warning"])
def test_the_adaptive_solutions_take_over_where_the_companion_does_not_apply(tmp_path, why):
    data = seed_deck(duration=1.0, warn_error=0.5)
    integrator = None
    if why == "kr-alpha":
        integrator = "kr-alpha"
    elif why == "exact":
        data["analysis"]["kinematics"] = "exact"
    elif why == "exact in space":
        from test_body3d import plane_and_prism

        data = plane_and_prism("chang")[1]
        data["analysis"].update(kinematics="exact", duration=0.5, warn_error=0.5, estimate_error=True)
    elif why == "spectra":
        data["output"] = {"spectra": {"damping": [0.05], "periods_s": [0.1, 0.5]}}
    else:  # the check moves the history by 4e-5, more than the warning: the adaptive solutions decide
        data["analysis"].update(dt=0.005, warn_error=1e-6)
        integrator = "chang"  # (at the deck's dt: by default a finer step would be tried first)
    res = rbhyst.run(write_deck(tmp_path, data), integrator=integrator)
    assert "companion" not in res.accuracy and res.accuracy["reference"]["rtol"] == pytest.approx(1e-9)


@pytest.mark.parametrize("body", ["plane", "turned box"])
def test_the_largest_change_of_every_column_is_the_table_s_own_difference(tmp_path, body):
    """What the companion compares (history.Layout.largest_change of changes of the coordinates,
    velocities and forces, one compiled pass) is the largest difference of every estimate column
    of the two tables: the table is linear in them with small rotations (the load and the
    support cancel). The seed's body with points and Rayleigh damping; a box in space whose
    inertia makes it run in its principal axes (its rows turned back to the deck's). Changes
    taken every other row of larger arrays (the probe's views) give the same to the bit."""
    from test_body3d import box_scene, rotation_matrix

    from rbhyst.solve.history import Raw, estimate_columns, largest_abs

    if body == "plane":
        data = seed_deck(duration=0.5)
        data["damping"] = {"rayleigh": {"ratio": 0.05, "modes": [1, 3]}}
        data["output"] = {"points": [{"name": "top", "point": [0.0, 2.0]}, {"name": "corner", "point": [0.8, 0.0]}]}
    else:
        data = box_scene(rotation_matrix([1.0, 2.0, 3.0], 0.4))
        data["analysis"].update(duration=0.05, kinematics="small")
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    layout = res.layout
    assert len(layout.points) >= 1 and (layout.damped if body == "plane" else res.system.frame is not None)
    rng = np.random.default_rng(5)
    rows, n, ne = 301, res.system.n, layout.system.bvec.shape[0]
    t = np.linspace(0.0, 0.3, rows)
    d, v, f = rng.normal(size=(rows, n)) * 1e-3, rng.normal(size=(rows, n)) * 1e-2, rng.normal(size=(rows, ne)) * 1e3
    dd, dv, df = rng.normal(size=d.shape) * 1e-6, rng.normal(size=v.shape) * 1e-5, rng.normal(size=f.shape)
    u, e = np.zeros((rows, ne)), np.zeros((rows, 4))
    one = layout.table(Raw(t, d, v, u, f, e))
    two = layout.table(Raw(t, d - dd, v - dv, u, f - df, e))
    index = [c for _, c, _ in estimate_columns(layout)]
    want = largest_abs(one[:, index] - two[:, index])
    whole = layout.largest_change(dd, dv, df)
    assert whole.shape == want.shape and len(whole) > 3 * n + 8
    np.testing.assert_allclose(whole, want, rtol=1e-7)
    wide = [np.repeat(x, 2, axis=0) for x in (dd, dv, df)]
    assert not wide[0][::2].flags.c_contiguous
    np.testing.assert_array_equal(layout.largest_change(*(x[::2] for x in wide)), whole)


def _python_and_one_call(planned, tap, every, check, largest):
    """(the Python path's changes: Companion.run's and Companion.probe's, each through
    Layout.largest_change; estimate_in_one_call's (changed, moved)) of one tapped run."""
    from rbhyst.solve.companion import Companion, estimate_in_one_call
    from rbhyst.solve.estimate import COMPANION_PROBE, error_scales
    from rbhyst.solve.history import estimate_columns

    res = planned.run(keep=False, tap=tap)
    layout = res.layout
    cols = estimate_columns(layout)
    columns = [c for _, c, _ in cols]
    peaks = np.maximum(np.abs(res.extremes.max[columns]), np.abs(res.extremes.min[columns]))
    scales = error_scales(peaks, [k for k, _, _ in cols], [f for _, _, f in cols], res.system)
    changed, moved, _ = estimate_in_one_call(planned, tap, every, layout, scales, check, largest, COMPANION_PROBE)
    companion = Companion(planned, tap, every)
    diff, _ = companion.run()
    probed, _ = companion.probe(COMPANION_PROBE)
    return (layout.largest_change(*diff), layout.largest_change(*probed)), (changed, moved), scales


@pytest.mark.parametrize("scene_name", ["seed", "shock split in 14", "damped with points"])
@pytest.mark.parametrize("every", [1, 3, 7])
def test_the_estimate_in_one_call_is_the_companion_and_its_probe_to_the_bit(tmp_path, scene_name, every):
    """The companion, its probe and their largest changes in one compiled call (kernels.estimate,
    where the check has no core of its own) give what Companion.run and Companion.probe give
    through Layout.largest_change, bit for bit: the compared nodes worked out in the call from
    the segments' substeps (a shock that splits steps in 14 around it, every 3rd or 7th output
    step compared), the forces re-driven where steps were split, Rayleigh damping and points;
    the probe runs only where the companion's estimate exceeds ``check``, none past ``largest``
    (where the companion's changes are given all the same: a screen's pass takes them)."""
    from rbhyst.results.analysis import plan, scene
    from rbhyst.solve.choose import companion_of as _companion
    from rbhyst.solve.estimate import scaled_errors

    data = seed_deck(duration=0.6, dt=2e-3)
    if scene_name == "shock split in 14":
        data["excitation"] = {"support": {"x1": {"type": "half-sine", "amplitude": 20.0, "units": "g",
                                                 "duration": 0.0061, "start": 0.0507}}}
    elif scene_name == "damped with points":
        data["damping"] = {"rayleigh": {"ratio": 0.05, "modes": [1, 2]}}
        data["output"] = {"points": [{"name": "top", "point": [0.3, 1.0]}, {"name": "side", "point": [-0.7, 0.0]}]}
    system, settings = scene(rbhyst.load_deck(write_deck(tmp_path, data)))
    planned = plan(system, settings)
    assert (planned.substeps.max() == 14) == (scene_name == "shock split in 14")
    planned, tap = _companion(planned)
    (want_c, want_p), (changed, moved), scales = _python_and_one_call(planned, tap, every, -1.0, np.inf)
    np.testing.assert_array_equal(changed, want_c)
    np.testing.assert_array_equal(moved, want_p)
    worst = float(np.max(scaled_errors(want_c, scales)))
    assert worst > 0
    planned, tap = _companion(plan(system, settings))
    (_, _), (changed, moved), _ = _python_and_one_call(planned, tap, every, worst, np.inf)
    np.testing.assert_array_equal(changed, want_c)
    assert moved is None  # (at the check itself: no probe)
    planned, tap = _companion(plan(system, settings))
    (_, _), (changed, moved), _ = _python_and_one_call(planned, tap, every, -1.0, 0.999 * worst)
    np.testing.assert_array_equal(changed, want_c)  # (past ``largest`` the numbers, for the caller to judge)
    assert moved is None
