"""A symmetric scene's cross-axis response is rounding (1e-18 m beside 4e-3 m): summary.json
lists those columns in ``at_rest``, and the console, the tables and report.html print them as 0,
never as a response; the files keep their values."""

from __future__ import annotations

import json
import re

import pytest

from conftest import invoke, square_linear_deck, write_deck
from test_report import Page, check_page

#: the columns a square on four springs, shaken along x1, leaves at rest (by symmetry)
ACROSS = {"u2_m", "theta3_rad", "at2_m_s2", "alphat3_rad_s2", "R2_N", "R3_Nm", "top_u2_m", "top_at2_m_s2",
          "e3_u_m", "e3_f_N", "e4_u_m", "e4_f_N"}


@pytest.fixture(scope="module")
def symmetric(tmp_path_factory):
    folder = tmp_path_factory.mktemp("at_rest")
    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.2, "frequency_hz": 2.0, "units": "g",
                                             "cycles": 3}}}
    data["analysis"] = {"dt": 0.002, "duration": 2.0}
    data["output"] = {"points": [{"name": "top", "point": [0.0, 0.5]}]}
    code, err = invoke("run", write_deck(folder, data), "--out", folder / "out", "--report", "--no-plots")
    assert code == 0, err
    return folder / "out", err


def test_the_cross_axis_columns_are_listed_at_rest_and_keep_their_values(symmetric):
    out, _ = symmetric
    s = json.loads((out / "summary.json").read_text())
    assert set(s["at_rest"]) == ACROSS
    # the test means something: rounding, not zero, beside a response along x1 (independently:
    # each below 1e-9 of its counterpart along x1)
    assert 0 < s["peaks"]["u2_m"] < 1e-9 * s["peaks"]["u1_m"]
    assert 0 < s["peaks"]["at2_m_s2"] < 1e-9 * s["peaks"]["at1_m_s2"]
    assert 0 < s["peaks"]["e3_f_N"] < 1e-9 * s["peaks"]["e1_f_N"]
    assert s["peaks"]["u1_m"] > 1e-3


def test_the_console_prints_them_as_0(symmetric):
    _, err = symmetric
    line = next(x for x in err.splitlines() if x.startswith("chang"))
    assert "|u2| = 0 m, |theta3| = 0 rad" in line and "|at2| = 0 m/s2 (0 g)" in line
    assert re.search(r"\|u1\| = 0\.004\d+ m", line)
    rows = {x.split()[0]: x.split() for x in err.splitlines() if re.match(r"\s+e\d ", x)}
    assert rows["e3"][-2:] == ["0", "0"] and rows["e4"][-2:] == ["0", "0"]
    assert float(rows["e1"][-2]) > 800
    assert not re.search(r"\de-1\d", err)


def test_the_report_prints_them_as_0_with_no_time(symmetric):
    out, _ = symmetric
    page = check_page(out)  # (every number still the file's, shown as its kind says)
    shown = {a["data-src"]: (a["data-kind"], v.strip()) for a, v in page.numbers}
    for c in ACROSS:
        assert shown[f"summary.json:peaks.{c}"] == ("rest", "0"), c
    for c in ("u2_m", "at2_m_s2", "R2_N"):
        assert shown[f"summary.json:extremes.{c}.max"] == ("rest", "0")
        assert f"summary.json:extremes.{c}.time_of_max_s" not in shown  # the time of a peak of rounding: none
    assert shown["summary.json:peaks.u1_m"][0] == "g" and float(shown["summary.json:peaks.u1_m"][1]) > 1e-3
    text = " ".join(Page(re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", (out / "report.html").read_text())).text)
    assert "0: at rest, to rounding" in text
    assert not re.search(r"\de-(1\d|[2-9]\d)", text)  # no rounding noise anywhere on the page
