"""Input a new user got wrong without being told: each gets rbhyst's own frame (one ``error:``
line per problem, every problem at once, exit 2) or a warning with its numbers."""

from __future__ import annotations

import numpy as np
import pytest

import rbhyst
from conftest import invoke, seed_deck, square_linear_deck, write_deck

G = 9.80665


def test_gravity_in_mm_s2_is_a_mistake_with_its_numbers(tmp_path):
    """A mm/s2 slip once ran silently to a static u2 of -490 m on a 1 m body; then it warned and
    ran to a 12 m sag. It is the deck's mistake (exit 2) unless the deck says it means it
    (body.gravity_check = false), and then its static deflection is still warned."""
    data = square_linear_deck()
    data["body"]["gravity"] = [0.0, -G * 1000.0]
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.1, "frequency_hz": 2.0, "units": "g"}}}
    with pytest.raises(rbhyst.InputError) as err:
        rbhyst.run(write_deck(tmp_path, data), estimate=False)
    [line] = err.value.problems
    assert line.startswith("body.gravity: |g| = 9806.65 m/s2 is 1000 times the standard 9.80665 m/s2")
    assert "was it given in mm/s2?" in line
    data["body"]["gravity_check"] = False
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    said = " ".join(res.warnings)
    assert "static deflection under the weight is 12.26 m" in said  # m g / 2k = 500 * 9806.65 / 4e5
    assert any(n.startswith("body.gravity: the weight 4.90332e+06 N rests on the elements") for n in res.notes)


def test_standard_gravity_shows_its_preload_and_warns_of_nothing(tmp_path):
    data = square_linear_deck()
    data["body"]["gravity"] = [0.0, -G]
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.1, "frequency_hz": 2.0, "units": "g"}}}
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    assert not [w for w in res.warnings if "gravity" in w]
    [note] = [n for n in res.notes if n.startswith("body.gravity")]
    assert "u2 = -0.01226 m" in note  # 500 kg * g / (2 x 2e5 N/m)


def test_an_element_beyond_its_stroke_under_the_weight_alone_is_warned(tmp_path):
    data = square_linear_deck()
    data["body"]["gravity"] = [0.0, -G]
    data["elements"][2]["stroke"] = 0.005
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.01, "frequency_hz": 2.0, "units": "g"}}}
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    assert any("element e3 ('lin') is beyond its stroke under the weight alone: -0.01226 m" in w for w in res.warnings)


def test_a_damper_of_zero_keeps_its_columns_with_no_force(tmp_path):
    """A sweep's no-damper baseline: c = 0 is accepted and changes no number."""
    data = seed_deck(duration=0.5)
    plain = rbhyst.run(write_deck(tmp_path, data, "plain"), estimate=False)
    data["dampers"] = [{"vertex": 1, "angle_deg": 0.0, "c": 0.0}]
    zero = rbhyst.run(write_deck(tmp_path, data, "zero"), estimate=False)
    assert "d1_f_N" in zero.columns and np.all(zero.column("d1_f_N") == 0.0)
    np.testing.assert_array_equal(zero.column("u1_m"), plain.column("u1_m"))
    np.testing.assert_array_equal(zero.column("at1_m_s2"), plain.column("at1_m_s2"))


def test_a_negative_stroke_is_one_line(tmp_path):
    data = seed_deck()
    data["elements"][1]["stroke"] = -0.01
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots")
    assert code == 2
    assert err.splitlines() == ["error: elements[2].stroke: -0.01 must be a positive number (m) or "
                                "[lower, upper] with lower < 0 < upper (m)"]


def test_an_empty_deck_names_every_missing_section(tmp_path):
    deck = tmp_path / "empty.toml"
    deck.write_text("")
    code, err = invoke("run", deck)
    assert code == 2
    assert err.splitlines() == ["error: hysteresis: required key is missing", "error: body: required for an analysis",
                                "error: elements: required for an analysis ([[elements]] or [[isolators]])",
                                "error: analysis: required for an analysis"]
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("args, lines", [
    (["run", "DECK", "--dt", "abc"], ["error: --dt: 'abc' is not valid: input should be a valid number, unable to "
                                      "parse string as a number"]),
    (["run", "DECK", "--dt", "abc", "--tolerance=x"],
     ["error: --dt: 'abc' is not valid: input should be a valid number, unable to parse string as a number",
      "error: --tolerance: 'x' is not valid: input should be a valid number, unable to parse string as a number"]),
    (["make-record", "OUT.csv", "--pga", "-1"], ["error: --pga: '-1' is not valid: input should be greater than or "
                                                 "equal to 0"]),
    (["spectrum", "REC.csv"], ["error: --units: required"]),
    (["spectrum"], ["error: RECORD: required", "error: --units: required"]),
])
def test_command_line_mistakes_get_rbhyst_s_frame(tmp_path, args, lines):
    """Not the library's boxed usage text with a {deck} placeholder: one error line each, all at once."""
    deck = write_deck(tmp_path, seed_deck())
    args = [str(deck) if a == "DECK" else str(tmp_path / a) if a.endswith(".csv") else a for a in args]
    code, err = invoke(*args)
    assert code == 2
    assert err.splitlines() == lines
    assert list(tmp_path.iterdir()) == [deck]


@pytest.mark.parametrize("mass", [5e-324, 1e-320])
def test_a_mass_too_small_to_divide_by_is_one_line(tmp_path, mass):
    """A positive mass the deck's schema takes, but whose inverse overflows (M^-1 is in every
    step): one line naming body.mass, exit 2, not numpy's LinAlgError from the run's set-up."""
    data = seed_deck(duration=0.05)
    data["body"]["mass"] = mass
    code, err = invoke("run", write_deck(tmp_path, data), "--no-plots")
    assert code == 2, err
    [line] = err.strip().splitlines()
    assert line.startswith("error: body.mass: the body's mass matrix has entries ") and "too small to divide by" in line


# ------------------------------------------------------------------ in the user's words

PYDANTIC_WORDS = ("constrained-", "Input should be", "literal_error", "function-after", "function-before",
                  "valid list", "valid dictionary", "tagged-union")


def run_error(tmp_path, data) -> list[str]:
    out = tmp_path / "o"
    code, err = invoke("run", write_deck(tmp_path, data), "--out", out, "--no-plots")
    assert code == 2 and not out.exists(), err
    lines = err.splitlines()
    assert all(line.startswith("error: ") for line in lines) and not any(w in err for w in PYDANTIC_WORDS), err
    return lines


@pytest.mark.parametrize("where, value, line", [
    (("damping",), {"rayleigh": {"ratio": 1.5, "modes": [1, 2]}}, "error: damping.rayleigh.ratio: must be less than 1"),
    (("analysis", "kinematics"), "big", "error: analysis.kinematics: must be 'auto', 'small' or 'exact'"),
    (("analysis", "dt"), "abc", "error: analysis.dt: must be a valid number"),
    (("body", "mass"), -1.0, "error: body.mass: must be greater than 0"),
])
def test_a_wrong_value_is_said_in_rbhyst_s_words(tmp_path, where, value, line):
    data = seed_deck(duration=0.2)
    target = data
    for key in where[:-1]:
        target = target[key]
    target[where[-1]] = value
    assert run_error(tmp_path, data) == [line]


def test_a_record_and_a_signal_at_once_are_said_to_be_both(tmp_path):
    data = seed_deck(duration=0.2)
    data["excitation"]["support"]["x1"]["file"] = "x1.csv"
    assert run_error(tmp_path, data) == [
        "error: excitation.support.x1: both a record (`file`) and a signal (`type`): give one; a record takes no `type`"]


def test_a_byte_order_mark_is_accepted_in_decks_and_records(tmp_path):
    """Windows Notepad saves UTF-8 with a byte-order mark: it is not text, and rbhyst reads past it."""
    (tmp_path / "rec.csv").write_text("time_s,acc_g\n0.0,0.0\n0.01,0.05\n0.02,-0.03\n0.03,0.0\n", encoding="utf-8-sig")
    data = seed_deck(duration=0.1)
    data["excitation"]["support"] = {"x1": {"file": "rec.csv", "units": "g"}}
    path = write_deck(tmp_path, data)
    path.write_text(path.read_text(), encoding="utf-8-sig")
    assert path.read_bytes().startswith(b"\xef\xbb\xbf")
    code, err = invoke("run", path, "--out", tmp_path / "o", "--no-plots")
    assert code == 0, err


def test_a_spreadsheet_export_with_decimal_commas_is_named(tmp_path):
    (tmp_path / "rec.csv").write_text("time_s;acc_g\n0,00;0,01\n0,01;0,02\n0,02;-0,015\n")
    data = seed_deck(duration=0.1)
    data["excitation"]["support"] = {"x1": {"file": "rec.csv", "units": "g"}}
    [line] = run_error(tmp_path, data)
    assert "rec.csv:2: '0,00;0,01' looks like a spreadsheet's export with decimal commas" in line
    assert "export it with '.' as the decimal separator" in line


def test_every_command_line_problem_is_said_at_once(tmp_path):
    code, err = invoke("transmissibility", write_deck(tmp_path, seed_deck()), "--direction", "x3",
                       "--amplitude", "0.2,abc", "--units", "gg")
    assert code == 2
    assert err.splitlines() == [
        "error: --amplitude: 'abc' is not a number",
        "error: frequencies: --frequencies, or --from, --to and --count (--from, --to, --count missing)",
        "error: --direction: 'x3': x1 or x2 (x3, the vertical, for a deck in space)",
        "error: --units: 'gg': g or m/s2"]


def test_a_record_that_starts_late_is_noted(tmp_path):
    (tmp_path / "late.csv").write_text("time_s,acc_g\n5.0,0.0\n5.01,0.02\n5.02,-0.015\n5.03,0.0\n")
    data = seed_deck(duration=5.1)
    data["excitation"]["support"] = {"x1": {"file": "late.csv", "units": "g"}}
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    assert any(n.startswith("excitation.support.x1: late.csv: its time column starts at 5 s: the support is at rest")
               for n in res.notes)


def test_another_deck_s_results_replaced_are_said(tmp_path):
    out = tmp_path / "o"
    first, second = seed_deck(duration=0.1), seed_deck(duration=0.1)
    second["title"] = "cabinet B"
    assert invoke("run", write_deck(tmp_path, first, "a"), "--out", out, "--no-plots")[0] == 0
    code, err = invoke("run", write_deck(tmp_path, second, "b"), "--out", out, "--no-plots")
    assert code == 0 and f"note: {out}: replaces the results of another deck, 'seed scene', that were there" in err
    second["analysis"]["dt"] = 5e-4  # the same deck, edited: its own results, replaced as meant
    code, err = invoke("run", write_deck(tmp_path, second, "b"), "--out", out, "--no-plots")
    assert code == 0 and "replaces the results" not in err


def test_another_command_s_results_replaced_are_said(tmp_path):
    """A study into a run's folder replaces the run's files: said before it writes; the same
    command again (its own results) and an empty folder say nothing."""
    out = tmp_path / "o"
    deck = write_deck(tmp_path, seed_deck(duration=0.05))
    assert invoke("run", deck, "--out", out, "--no-plots")[0] == 0
    study = ("study", deck, "--out", out, "--no-plots", "--integrators", "chang", "--dt", "0.005")
    code, err = invoke(*study)
    assert code == 0, err
    assert f"note: {out}: replaces the results of rbhyst run that were there" in err
    code, err = invoke(*study)
    assert code == 0 and "replaces the results" not in err
    code, err = invoke("run", deck, "--out", out, "--no-plots")
    assert code == 0 and f"note: {out}: replaces the results of rbhyst study that were there" in err
    code, err = invoke("run", deck, "--out", tmp_path / "fresh", "--no-plots")
    assert code == 0 and "replaces the results" not in err
