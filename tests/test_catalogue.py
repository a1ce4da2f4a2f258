"""rbhyst calibrate --catalogue: a symmetric VRM set from a catalogue's effective stiffness and damping
at a few amplitudes (and static load-deflection points). The catalogues are made here from known
sets with the closed-form steady loop of test_effective; the fitted set is checked with it too."""

from __future__ import annotations

import json
import math

import pytest
from conftest import invoke, write_deck
from test_effective import steady_loop

from rbhyst.model.deck import load_deck
from rbhyst.model.vrm import loop

WRI_LIKE = {"kb": 2.0e4, "f0": 800.0, "alpha": 200.0}
# seed Table 3's shear loading branch, mirrored into a symmetric set (exponential stiffening)
SHEAR = {"kb": 220000.0, "f0": 1150.0, "alpha": 680.0, "beta1": 100.0, "beta2": 300.0}


def mirrored(b: dict) -> dict:
    un = {k: (-v if k in ("beta1", "beta2", "gamma3") else v) for k, v in b.items()}
    return {"loading": dict(b), "unloading": un}


def write_catalogue(path, rows, header="amplitude_m,k_eff_N_m,beta_eff"):
    path.write_text("# made from a known set\n" + header + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


def catalogue_of(st: dict, amplitudes) -> list[tuple]:
    rows = []
    for a in amplitudes:
        e = steady_loop(st, a)
        rows.append((a, f"{e['k_eff']:.5g}", f"{e['beta_eff']:.4g}"))  # as a catalogue prints them
    return rows


def init_deck(folder, b: dict):
    return write_deck(folder, {"hysteresis": {"iso": {"loading": b, "unloading": b}}}, "init")


def fitted(out) -> dict:
    """The fitted set as fitted.toml holds it, as branch dicts."""
    h = load_deck(out / "fitted.toml").hysteresis["iso"]
    return {"loading": h.loading.model_dump(), "unloading": h.unloading.model_dump()}


def check_matched(st_fit: dict, rows, within=0.02):
    for a, k, beta in rows:
        e = steady_loop(st_fit, a)
        assert e["k_eff"] == pytest.approx(float(k), rel=within), a
        assert e["beta_eff"] == pytest.approx(float(beta), rel=within), a


def test_three_rows_of_a_known_set_are_matched_within_2_percent(tmp_path):
    truth = mirrored(WRI_LIKE)
    rows = catalogue_of(truth, [0.002, 0.008, 0.02])
    cat = write_catalogue(tmp_path / "wri.csv", rows)
    init = init_deck(tmp_path, {"kb": 5e4, "f0": 300.0, "alpha": 50.0})
    code, err = invoke("calibrate", "--catalogue", cat, "--set", "iso", "--init", init)
    assert code == 0, err
    out = tmp_path / "results" / "wri-calibrate"
    assert sorted(p.name for p in out.iterdir()) == [".rbhyst.json", "effective.csv", "fit.json", "fitted.toml",
                                                     "loops.png"]
    check_matched(fitted(out), rows)
    fit = json.loads((out / "fit.json").read_text())
    assert fit["largest_misfit"] <= 0.02 and fit["free"] == ["kb", "f0", "alpha"]
    assert "warning" not in err
    # three rows of k_eff and beta_eff pin the three parameters down: the set comes back
    got = fitted(out)["loading"]
    for k, v in WRI_LIKE.items():
        assert got[k] == pytest.approx(v, rel=0.01), k


def test_exponential_terms_free_match_a_stiffening_set(tmp_path):
    truth = mirrored(SHEAR)
    rows = catalogue_of(truth, [0.002, 0.005, 0.01])
    cat = write_catalogue(tmp_path / "shear.csv", rows)
    init = init_deck(tmp_path, {"kb": 1e5, "f0": 800.0, "alpha": 300.0, "beta1": 50.0, "beta2": 100.0})
    base = ("calibrate", "--catalogue", cat, "--set", "iso", "--init", init)
    code, err = invoke(*base, "--out", tmp_path / "three")
    assert code == 0, err
    three = json.loads((tmp_path / "three" / "fit.json").read_text())["largest_misfit"]
    code, err = invoke(*base, "--free", "kb,f0,alpha,beta1,beta2", "--out", tmp_path / "five")
    assert code == 0, err
    check_matched(fitted(tmp_path / "five"), rows)
    assert json.loads((tmp_path / "five" / "fit.json").read_text())["largest_misfit"] <= 0.02 < three


def test_a_static_force_row_is_matched_on_first_loading(tmp_path):
    truth = mirrored(WRI_LIKE)
    rows = [(a, k, b, "") for a, k, b in catalogue_of(truth, [0.002, 0.02])]
    # first loading from rest, eq. 14 from (0, 0): f = c+(d) - (c+(0) - 0) exp(-alpha d)
    d = 0.01
    force = 2e4 * d + 800 - 800 * math.exp(-200 * d)
    rows.append((d, "", "", f"{force:.6g}"))
    cat = write_catalogue(tmp_path / "with_static.csv", rows, "amplitude_m,k_eff_N_m,beta_eff,force_N")
    code, err = invoke("calibrate", "--catalogue", cat, "--set", "iso", "--init",
                       init_deck(tmp_path, {"kb": 5e4, "f0": 300.0, "alpha": 50.0}))
    assert code == 0, err
    out = tmp_path / "results" / "with_static-calibrate"
    fit = json.loads((out / "fit.json").read_text())
    static = [r for r in fit["rows"] if "force_N" in r]
    assert len(static) == 1 and abs(static[0]["force_N"]["misfit"]) <= 0.02
    p = load_deck(out / "fitted.toml").hysteresis["iso"].array()
    assert loop(p, [0.0, d])[0][-1] == pytest.approx(force, rel=0.02)


def test_a_catalogue_no_such_set_can_match_says_by_how_much(tmp_path):
    """k_eff = kb + f0 tanh(alpha A) / A cannot grow with A: the best set misses, and says so."""
    cat = write_catalogue(tmp_path / "stiffening.csv", [(0.002, 1e5, 0.05), (0.02, 3e5, 0.3)])
    code, err = invoke("calibrate", "--catalogue", cat, "--set", "iso", "--init",
                       init_deck(tmp_path, {"kb": 5e4, "f0": 300.0, "alpha": 50.0}))
    assert code == 0, err
    fit = json.loads((tmp_path / "results" / "stiffening-calibrate" / "fit.json").read_text())
    assert fit["largest_misfit"] > 0.02
    warning = [ln for ln in err.splitlines() if ln.startswith("warning:")]
    assert len(warning) == 1 and f"{fit['largest_misfit']:.1%}" in warning[0]


@pytest.mark.parametrize("text, message", [
    ("amplitude_m,k_eff_N_m,beta_eff\n0.002,1e5,0.1\n0.01,x,0.2\n", "bad.csv:3: k_eff_N_m: 'x' is not a number"),
    ("amplitude_m,k_eff_N_m,beta_eff\n0.002,1e5,0.1\n", "1 row(s) with k_eff_N_m and beta_eff; at least 2"),
    ("amplitude_m,k_eff_N_m,beta_eff\n0.002,1e5,0.1\n0.01,1e5,1.2\n", "bad.csv:3: beta_eff: 1.2: a damping ratio"),
    ("amplitude_m,k_eff,beta_eff\n0.002,1e5,0.1\n", "bad.csv:1: column 'k_eff': not one of"),
    ("amplitude_m,k_eff_N_m,beta_eff\n0.002,1e5,0.1\n-0.01,1e5,0.2\n", "bad.csv:3: amplitude_m: -0.01: a number > 0"),
    ("amplitude_m,k_eff_N_m,beta_eff\n0.002,1e5\n0.01,1e5,0.2\n", "bad.csv:2: 2 values for 3 columns"),
])
def test_a_bad_catalogue_is_one_line_exit_2_nothing_written(tmp_path, text, message):
    (tmp_path / "bad.csv").write_text(text)
    code, err = invoke("calibrate", "--catalogue", tmp_path / "bad.csv", "--set", "iso", "--init",
                       init_deck(tmp_path, WRI_LIKE))
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], err
    assert not (tmp_path / "results").exists()


def test_a_loop_and_a_catalogue_together_or_neither_are_refused(tmp_path):
    cat = write_catalogue(tmp_path / "c.csv", catalogue_of(mirrored(WRI_LIKE), [0.002, 0.02]))
    init = init_deck(tmp_path, WRI_LIKE)
    code, err = invoke("calibrate", cat, "--catalogue", cat, "--set", "iso", "--init", init)
    assert code == 2 and "not both" in err
    code, err = invoke("calibrate", "--set", "iso", "--init", init)
    assert code == 2 and "--catalogue" in err
    code, err = invoke("calibrate", "--catalogue", cat, "--set", "iso", "--init", init, "--free", "kb+")
    assert code == 2 and "--free: 'kb+'" in err
