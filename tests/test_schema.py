"""`rbhyst schema`: the deck's JSON Schema from its pydantic models. Every deck rbhyst reads
validates against it (the sample decks, in TOML and as YAML, the short forms a field validator
widens); a misspelt key, a wrong type or a value out of range does not."""

from __future__ import annotations

import copy
import json
import tomllib

import jsonschema
import pytest
import yaml
from conftest import DECKS, invoke, seed_deck, square_linear_deck, write_deck
from test_equipment import damped_square, hanging_deck
from test_isolators import isolator_cabinet, space_deck

from rbhyst.errors import InputError
from rbhyst.model.deck import load_deck, parse_deck, read_mapping
from rbhyst.model.schema import deck_schema

#: every deck of decks/ and its folders (the tutorials' too), sweep files (their `deck` key) aside
SAMPLES = sorted(p for p in DECKS.rglob("*.toml")
                 if "results" not in p.parts and "deck" not in tomllib.loads(p.read_text()))


@pytest.fixture(scope="module")
def validator():
    schema = deck_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def problems(validator, data: dict) -> list[str]:
    return [f"{'.'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(data)]


def every_error(validator, data: dict):
    """Each error with those inside it (a key of an optional table fails inside its anyOf)."""
    todo = list(validator.iter_errors(data))
    while todo:
        e = todo.pop()
        yield e
        todo += e.context or []


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_every_sample_deck_validates_in_toml_and_as_yaml(validator, path, tmp_path):
    load_deck(path)  # rbhyst reads it
    data = tomllib.loads(path.read_text())
    assert problems(validator, data) == []
    as_yaml = tmp_path / (path.stem + ".yaml")
    as_yaml.write_text(yaml.safe_dump(data))
    assert problems(validator, read_mapping(as_yaml)) == []


@pytest.mark.parametrize("make", [seed_deck, square_linear_deck, hanging_deck, lambda: damped_square(0.05),
                                  isolator_cabinet, lambda: space_deck()])
def test_the_tests_scenes_validate(validator, make):
    data = make()
    parse_deck(data)
    assert problems(validator, data) == []


def test_the_short_forms_a_validator_widens_validate(validator):
    """One damping ratio for a list of them (and out of range, neither form)."""
    data = seed_deck()
    data["output"] = {"spectra": {"damping": 0.02}}
    parse_deck(data)
    assert problems(validator, data) == []
    data["output"]["spectra"]["damping"] = 1.5
    with pytest.raises(InputError):
        parse_deck(data)
    assert problems(validator, data)


def test_integrators_by_name(validator):
    data = seed_deck(integrator="newmark")
    assert problems(validator, data) == []
    data["analysis"]["integrator"] = "nemwark"
    with pytest.raises(InputError):
        parse_deck(data)
    assert problems(validator, data)


@pytest.mark.parametrize("where, key", [((), "tittle"), (("analysis",), "dtt"), (("body",), "mas"),
                                        (("hysteresis", "wri_axial", "loading"), "kbb"),
                                        (("elements", 0), "hysterisis")])
def test_a_misspelt_key_is_rejected_where_it_stands(validator, where, key):
    data = seed_deck()
    node = data
    for part in where:
        node = node[part]
    node[key] = 1.0
    with pytest.raises(InputError):
        parse_deck(data)  # rbhyst rejects it ...
    found = [e for e in every_error(validator, data) if key in e.message]
    assert found, problems(validator, data)  # ... and so does the schema, at that table
    assert any(list(e.absolute_path) == list(where) and "additional" in e.message.lower() for e in found)


@pytest.mark.parametrize("key, value", [(("body", "mass"), "heavy"), (("body", "mass"), -1.0),
                                        (("analysis", "dt"), 0.0), (("analysis", "kinematics"), "large"),
                                        (("hysteresis", "wri_axial", "loading", "alpha"), 0.0)])
def test_a_wrong_type_or_range_is_rejected(validator, key, value):
    data = copy.deepcopy(seed_deck())
    node = data
    for part in key[:-1]:
        node = node[part]
    node[key[-1]] = value
    with pytest.raises(InputError):
        parse_deck(data)
    assert problems(validator, data)


def test_descriptions_and_units_reach_the_schema():
    defs = deck_schema()["$defs"]
    assert defs["Branch"]["properties"]["kb"]["x-unit"] == "N/m"
    assert defs["Body"]["properties"]["mass"]["description"].endswith("[kg]")
    assert "output interval" in defs["Analysis"]["properties"]["integrator"]["description"]
    assert "Record_acceleration" in defs and not any("Literal" in name for name in defs)


def test_the_command_prints_it_and_writes_it(tmp_path):
    from typer.testing import CliRunner

    from rbhyst.cli import app

    res = CliRunner().invoke(app, ["schema"])
    assert res.exit_code == 0 and res.stderr == ""
    assert json.loads(res.stdout) == deck_schema()
    target = tmp_path / "deck.schema.json"
    code, out = invoke("schema", "--out", str(target))
    assert code == 0 and f"wrote {target}" in out
    assert json.loads(target.read_text()) == deck_schema()


def test_a_file_it_cannot_write_is_one_line_exit_2(tmp_path):
    code, out = invoke("schema", "--out", str(tmp_path / "no" / "such" / "folder.json"))
    assert code == 2
    lines = [line for line in out.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: --out ") and "Traceback" not in out


def test_a_deck_that_names_its_schema_still_runs(tmp_path):
    """The editor's line is a comment: rbhyst reads the deck as before."""
    path = write_deck(tmp_path, seed_deck())
    path.write_text("#:schema ./deck.schema.json\n" + path.read_text())
    assert load_deck(path).body is not None
