"""Fragility from a sweep: limit states on cases.csv's columns (and safe expressions of them),
median and beta by maximum likelihood on the stripes equal to an independent fit, bootstrap
intervals that contain them and come out the same for the same seed, refusals that say why,
and the intensity measures (scale, PGA, Sa) from the motions themselves."""

from __future__ import annotations

import csv
import json
import math
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from scipy.optimize import minimize
from scipy.special import gammaln
from scipy.stats import norm

from rbhyst.analyses.fragility import (curves, csv_text, fit_lognormal, fit_many, identification_problem,
                                       parse_quantity, evaluate, NotIdentified)
from rbhyst.model.deck import ACCEL_UNITS
from rbhyst.sweep import load_sweep
from conftest import DECKS, invoke, snapshot

G = ACCEL_UNITS["g"]
LEVELS = [0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0]
LIMIT_STATES = [
    {"name": "at1", "quantity": "peak_at1_m_s2", "limit": 4.0},
    {"name": "floor", "quantity": "max(peak_at1_m_s2, peak_at2_m_s2) / 9.80665", "limit": 0.5},
    {"name": "stroke", "quantity": "max(stroke_e1, stroke_e5)", "limit": 0.8},
    {"name": "u2", "quantity": "peak_u2_m", "limit": 0.001},
    {"name": "never", "quantity": "peak_u1_m", "limit": 1.0},
]


def read(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def project(folder: Path, fragility: dict | None = None, limit_states=LIMIT_STATES, scale=None) -> Path:
    """The seed deck cut to 2 s, two of its isolators given a stroke, over its two records (and
    the same two swapped) at ten scale levels."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copytree(DECKS / "records", folder / "records", dirs_exist_ok=True)
    deck = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    deck["analysis"].update(duration=2.0, estimate_error=False)
    deck["elements"][0]["stroke"] = 0.0025
    deck["elements"][2]["stroke"] = [-0.0022, 0.0026]
    (folder / "deck.toml").write_text(tomli_w.dumps(deck))
    x1 = {"file": "records/synthetic_x1.csv", "units": "g"}
    x2 = {"file": "records/synthetic_x2.csv", "units": "g"}
    sweep = {"deck": "deck.toml", "motions": [{"name": "syn", "x1": x1, "x2": x2},
                                              {"name": "swapped", "x1": x2, "x2": x1}],
             "scale": scale or {"factors": LEVELS}, "limit_states": limit_states}
    if fragility is not None:
        sweep["fragility"] = fragility
    path = folder / "sweep.toml"
    path.write_text(tomli_w.dumps(sweep))
    return path


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    path = project(tmp_path_factory.mktemp("fragility") / "p", {"bootstrap": 400, "seed": 3})
    code, err = invoke("sweep", path, "--workers", "1")
    assert code == 0, err
    return path, path.parent / "results" / "sweep"


def independent_fit(x, n, z) -> tuple[float, float]:
    """The maximum of the full binomial log-likelihood over (ln theta, beta): a grid, then
    Nelder-Mead from its best point (another parametrisation and another optimiser)."""
    x, n, z = map(np.asarray, (x, n, z))
    log_c = gammaln(n + 1) - gammaln(z + 1) - gammaln(n - z + 1)

    def nll(p):
        lt, b = p
        if b <= 0:
            return np.inf
        s = (np.log(x) - lt) / b
        return -np.sum(log_c + z * norm.logcdf(s) + (n - z) * norm.logcdf(-s))

    grid = [(lt, b) for lt in np.linspace(np.log(x.min()), np.log(x.max()), 61) for b in np.linspace(0.02, 2.0, 100)]
    best = min(grid, key=nll)
    res = minimize(nll, best, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-13, "maxiter": 20000})
    return math.exp(res.x[0]), res.x[1]


def test_median_and_beta_equal_an_independent_fit_and_the_intervals_contain_them(swept):
    path, out = swept
    cases = read(out / "cases.csv")
    assert len(cases) == 20 and all(c["status"] == "ok" for c in cases)
    fr = {r["limit_state"]: r for r in read(out / "fragility.csv")}
    assert list(fr) == [ls["name"] for ls in LIMIT_STATES]
    quantity = {"at1": lambda c: float(c["peak_at1_m_s2"]),
                "floor": lambda c: max(float(c["peak_at1_m_s2"]), float(c["peak_at2_m_s2"])) / 9.80665,
                "stroke": lambda c: max(float(c["stroke_e1"]), float(c["stroke_e5"]))}
    for name in ("at1", "floor", "stroke"):
        ls = next(s for s in LIMIT_STATES if s["name"] == name)
        reach = {lv: [quantity[name](c) >= ls["limit"] for c in cases if float(c["scale"]) == lv] for lv in LEVELS}
        n = [len(reach[lv]) for lv in LEVELS]
        z = [sum(reach[lv]) for lv in LEVELS]
        theta, beta = independent_fit(LEVELS, n, z)
        r = fr[name]
        assert r["status"] == "fitted", r["message"]
        assert float(r["median"]) == pytest.approx(theta, rel=1e-6)
        assert float(r["beta"]) == pytest.approx(beta, rel=1e-6)
        assert float(r["median_lo"]) <= float(r["median"]) <= float(r["median_hi"])
        assert float(r["beta_lo"]) <= float(r["beta"]) <= float(r["beta_hi"])
        assert (int(r["cases"]), int(r["reached"]), int(r["stripes"])) == (20, sum(z), 10)
        assert r["intensity"] == "scale factor" and int(r["bootstrap"]) == 400 and int(r["identified"]) > 200
        stripes = [s for s in read(out / "fragility_stripes.csv") if s["limit_state"] == name]
        assert [(float(s["im"]), int(s["cases"]), int(s["reached"])) for s in stripes] == list(zip(LEVELS, n, z))
        for s in stripes:  # the fitted curve at each stripe, inside its band
            p = norm.cdf(math.log(float(s["im"]) / float(r["median"])) / float(r["beta"]))
            assert float(s["p_fit"]) == pytest.approx(p, rel=1e-12, abs=1e-300)
            assert float(s["p_lo"]) <= float(s["p_fit"]) + 1e-12 and float(s["p_fit"]) <= float(s["p_hi"]) + 1e-12
    # refused per limit state, with why, and the sweep itself fine
    assert fr["u2"]["status"] == "not identified" and fr["u2"]["median"] == ""
    assert "the stripes separate at scale 1.5" in fr["u2"]["message"] and "beta -> 0" in fr["u2"]["message"]
    assert fr["never"]["message"].startswith("no case reaches the limit (0 of 20, scale 0.25 to 3)")
    about = json.loads((out / "sweep.json").read_text())["fragility"]
    assert about["intensity"] == "scale factor" and about["seed"] == 3 and len(about["limit_states"]) == 5
    assert (out / "fragility.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert {"fragility.csv", "fragility_stripes.csv", "fragility.png"} <= set(
        json.loads((out / ".rbhyst.json").read_text())["files"])


def test_the_bootstrap_is_seeded(swept):
    path, out = swept
    header = next(csv.reader(open(out / "cases.csv")))
    rows = list(csv.reader(open(out / "cases.csv")))[1:]
    plan = load_sweep(path).fragility
    first, again = (csv_text(plan, curves(plan, header, rows)) for _ in range(2))
    assert first == again == (out / "fragility.csv").read_text()
    plan.options = plan.options.model_copy(update={"seed": 4})
    other = {r["limit_state"]: r for r in csv.DictReader(csv_text(plan, curves(plan, header, rows)).splitlines())}
    mine = {r["limit_state"]: r for r in read(out / "fragility.csv")}
    assert all(other[k]["median"] == mine[k]["median"] for k in mine)  # the fit is the data's
    draw = ("median_lo", "median_hi", "beta_lo", "beta_hi", "identified")
    assert [other[k][c] for k in mine for c in draw] != [mine[k][c] for k in mine for c in draw]  # the band the draw's


def test_many_at_once_equal_one_at_a_time():
    rng = np.random.default_rng(0)
    x = np.array([0.2, 0.4, 0.6, 0.8, 1.0, 1.3])
    n = np.full(6, 7.0)
    p = norm.cdf(np.log(x / 0.7) / 0.4)
    z = rng.binomial(7, p, size=(60, 6)).astype(float)
    theta, beta = fit_many(x, n, z, (0.7, 0.4))
    checked = 0
    for r in range(len(z)):
        try:
            t1, b1 = fit_lognormal(x, n, z[r])
        except NotIdentified:
            assert np.isnan(theta[r])
            continue
        assert theta[r] == pytest.approx(t1, rel=1e-7) and beta[r] == pytest.approx(b1, rel=1e-7)
        checked += 1
    assert checked > 40


@pytest.mark.parametrize("x, n, z, start", [
    ([1.0, 2.0], [5, 5], [0, 0], "no case reaches the limit"),
    ([1.0, 2.0], [5, 5], [5, 5], "every case reaches the limit"),
    ([1.0], [5], [2], "one intensity level"),
    ([1.0, 2.0, 3.0], [5, 5, 5], [0, 0, 5], "the stripes separate: no case reaches the limit up to intensity 2"),
    ([1.0, 2.0, 3.0], [5, 5, 5], [0, 2, 5], "the stripes separate at intensity 2"),
])
def test_what_cannot_be_identified_says_why(x, n, z, start):
    why = identification_problem(*map(np.asarray, (x, n, z)))
    assert why.startswith(start)
    with pytest.raises(NotIdentified):
        fit_lognormal(x, n, z)


def test_a_falling_share_is_refused():
    with pytest.raises(NotIdentified, match="does not grow with the intensity"):
        fit_lognormal([1.0, 2.0, 3.0], [10, 10, 10], [8, 5, 2])


def test_expressions_evaluate_and_nothing_else_is_allowed():
    cols = {"a": np.array([1.0, -4.0, np.nan]), "b": np.array([2.0, 3.0, 1.0])}
    q = parse_quantity("max(abs(a), b) / 2 - -1 * min(a, b, 10)")
    np.testing.assert_array_equal(evaluate(q, cols, 3), [2.0, -2.0, np.nan])  # a missing value stays missing
    assert q.names == ("a", "b")
    np.testing.assert_array_equal(evaluate(parse_quantity("a / (b - 2)"), cols, 3)[:2], [np.nan, -4.0])
    for bad, says in [("__import__('os').system('x')", "is not allowed"), ("a ** 2", "is not allowed"),
                      ("a.real", "is not allowed"), ("[a]", "is not allowed"), ("lambda: 1", "is not allowed"),
                      ("'a'", "is not allowed"), ("a if b else 1", "is not allowed"), ("max(a)", "two arguments"),
                      ("abs(a, b)", "one argument"), ("max", "is a function"), ("a +", "not an expression"),
                      ("max(*a)", "is not allowed"), ("abs(x=a)", "is not allowed"), ("True", "is not allowed"),
                      ("a < b", "is not allowed"), ("1e999", "is not allowed")]:
        with pytest.raises(ValueError, match=says.replace("(", r"\(").replace("*", r"\*")):
            parse_quantity(bad)


def test_limit_state_mistakes_are_lines_naming_the_key_before_anything_runs(tmp_path):
    states = [{"name": "a", "quantity": "peak_u1", "limit": 1.0},
              {"name": "b", "quantity": "peak_u1_m ** 2", "limit": 1.0},
              {"name": "c", "quantity": "stroke_e3", "limit": 1.0},
              {"name": "a", "quantity": "peak_u1_m", "limit": 1.0}]
    path = project(tmp_path / "p", limit_states=states)
    before = snapshot(path.parent)
    code, err = invoke("sweep", path)
    assert code == 2 and "Traceback" not in err
    lines = err.splitlines()
    assert lines[0] == "error: limit_states[4].name: 'a' is the name of limit_states[1] too"
    assert lines[1].startswith("error: limit_states[1].quantity: peak_u1 is not a column of this sweep's "
                               "cases (did you mean peak_u1_m?)")
    assert lines[2].startswith("error: limit_states[2].quantity: 'peak_u1_m ** 2' is not allowed")
    assert lines[3].startswith("error: limit_states[3].quantity: stroke_e3 is not a column")
    assert lines[3].endswith("(stroke_e1, stroke_e5)")
    assert len(lines) == 4
    assert snapshot(path.parent) == before  # nothing written
    path = project(tmp_path / "p", {"intensity": "scale", "period_s": 1.0}, limit_states=states[:1])
    code, err = invoke("sweep", path)
    assert err.splitlines() == ["error: fragility.period_s: goes with intensity = \"sa_g\", not 'scale'"]


def test_the_intensity_measures_come_from_the_motions(tmp_path):
    from rbhyst.model.records import read_record
    from rbhyst.response import response_spectrum

    ac = {c: read_record(DECKS / "records" / f"synthetic_{c}.csv", None).series for c in ("x1", "x2")}
    pga = {c: float(np.abs(s.values).max()) for c, s in ac.items()}  # in g
    plan = load_sweep(project(tmp_path / "a", {"intensity": "pga_g"})).fragility
    assert plan.intensity.label == "PGA [g]"
    values = plan.intensity.values  # case k: motion syn (k <= 10) or swapped, at LEVELS[(k - 1) % 10]
    for k, v in values.items():
        assert v == pytest.approx(LEVELS[(k - 1) % 10] * max(pga.values()), rel=1e-12)
    plan = load_sweep(project(tmp_path / "b", {"intensity": "sa_g", "period_s": 0.5, "damping": 0.05})).fragility
    assert plan.intensity.label == "Sa(0.5 s; 5 %) [g]"
    # the larger component's Sa of the record followed by rest, as rbhyst spectrum computes it
    sa = max(float(response_spectrum(np.concatenate([s.values, np.zeros(200)]), s.dt, [0.5], [0.05]).sa.max())
             for s in ac.values())
    assert plan.intensity.values[1] == pytest.approx(0.25 * sa, rel=1e-6)
    assert plan.intensity.values[13] == pytest.approx(0.75 * sa, rel=1e-6)
    # targets of PGA: the level itself
    plan = load_sweep(project(tmp_path / "c", {"intensity": "pga_g"}, scale={"pga_g": [0.2, 0.4]})).fragility
    assert sorted(set(plan.intensity.values.values())) == [0.2, 0.4]


def test_resamples_that_separate_count_as_steps_in_the_intervals():
    """A resample whose stripes separate the cases is a step (beta -> 0), not a resample to drop:
    dropping them (12 % here) made the 5th percentile of beta a percentile of the others."""
    from rbhyst.analyses.fragility import bootstrap, fit_lognormal, probabilities

    x = np.array([1.0, 2.0, 3.0, 4.0])
    outcomes = [np.zeros(10), np.r_[np.ones(1), np.zeros(9)], np.r_[np.ones(9), np.zeros(1)], np.ones(10)]
    n = np.array([10.0] * 4)
    z = np.array([o.sum() for o in outcomes])
    fitted = fit_lognormal(x, n, z)
    theta, beta = bootstrap(x, outcomes, fitted, 2000, np.random.default_rng(7))
    step = beta == 0.0
    # stripe 2 resampled to no case reaching (0.9^10 of the time) or stripe 3 to every case
    # (as often) separates them: the step lies at the mixed stripe, or between 2 and 3 if both
    clean = 0.9 ** 10
    assert step.mean() == pytest.approx(1 - (1 - clean) ** 2, abs=0.03)
    both = np.isclose(theta, np.sqrt(6.0)) & step
    assert both.mean() == pytest.approx(clean ** 2, abs=0.02)
    assert np.all(np.isclose(theta[step], 2.0) | np.isclose(theta[step], 3.0) | both[step])
    assert np.all(beta[~step] > 0)
    assert np.percentile(beta[np.isfinite(beta)], 5) == 0.0  # honest: the data allow a step
    p = probabilities(np.array([2.0, 2.5, 3.0]), theta[both][:1], beta[both][:1])
    assert p.tolist() == [[0.0, 1.0, 1.0]]
