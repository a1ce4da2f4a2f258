"""The deck's JSON Schema, from its pydantic models (``rbhyst schema``): for editors that complete
and check a TOML or YAML deck as it is typed, and for the reference of every deck key.

pydantic writes the schema of the models' types and constraints. Added here: each key's
description from the comment the models give it (``#:`` above it or ``#`` beside it), its unit
(:data:`rbhyst.model.deck.KEY_UNITS`), the integrators by name, and the shorter forms that a
field validator turns into the full one before it validates (one damping ratio for a list):
the schema never rejects a deck rbhyst reads. It may accept one rbhyst rejects: what depends
on other keys or on numbers (crossing curves, a vertex that does not exist, a 2-D point in a
deck in space) rbhyst says when it reads the deck; the schema checks names, types and ranges.
"""

from __future__ import annotations

import ast
import functools
import inspect
import io
import textwrap
import tokenize
from typing import Any

from pydantic import BaseModel

#: the generic signals' schema names, by the units they are given in
_GENERIC_NAMES = {"Literal__g____m_s2____cm_s2___": "acceleration", "Literal__N____kN___": "force",
                  "Literal__N_m____kN_m___": "moment"}
#: the forms a "before" field validator accepts besides the annotated type: (model, field) -> schema
_SHORT_FORMS = {
    ("Spectra", "damping"): {"type": "number", "minimum": 0, "exclusiveMaximum": 1},
}
SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def deck_schema() -> dict:
    """The JSON Schema of a deck (draft 2020-12)."""
    from rbhyst.model import deck
    from rbhyst.model.integrators import INTEGRATORS

    schema = _renamed(deck.Deck.model_json_schema())
    defs = schema["$defs"]
    for model in _models(deck.Deck):
        name = _def_name(model)
        comments = field_comments(model)
        for field, prop in defs.get(name, schema if model is deck.Deck else {}).get("properties", {}).items():
            prop.pop("title", None)  # ("Periods S": pydantic's, from the name; the name says it)
            if field in comments and "description" not in prop:
                prop["description"] = comments[field]
            if (name, field) in _SHORT_FORMS:
                prop["anyOf"] = [_SHORT_FORMS[name, field], *prop.pop("anyOf", [_without_meta(prop)])]
                for k in ("type", "items", "minItems", "maxItems"):
                    prop.pop(k, None)
    integrator = defs["Analysis"]["properties"]["integrator"]
    integrator["anyOf"] = [{"enum": list(INTEGRATORS)}, {"type": "null"}]
    _add_units(schema, defs, ())
    schema["title"] = "rbhyst deck"
    return {"$schema": SCHEMA_DIALECT, **schema}


def _without_meta(prop: dict) -> dict:
    return {k: v for k, v in prop.items() if k not in ("default", "description", "title")}


def _renamed(schema: dict) -> dict:
    """The generic signals named by their units (``Sine_force``), not by pydantic's mangling."""
    import json

    text = json.dumps(schema)
    for mangled, plain in _GENERIC_NAMES.items():
        text = text.replace(mangled, plain)
    return json.loads(text)


def _def_name(model: type[BaseModel]) -> str:
    name = model.__name__
    for mangled_args, plain in (("[Literal['g', 'm/s2', 'cm/s2']]", "acceleration"),
                                ("[Literal['N', 'kN']]", "force"), ("[Literal['N m', 'kN m']]", "moment")):
        name = name.replace(mangled_args, "_" + plain)
    return name


def _models(root: type[BaseModel]) -> list[type[BaseModel]]:
    """Every model reachable from ``root``'s fields, root first."""
    seen: list[type[BaseModel]] = []

    def visit(tp: Any) -> None:
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if tp in seen:
                return
            seen.append(tp)
            for f in tp.model_fields.values():
                visit(f.annotation)
                for m in f.metadata:
                    visit(m)
        for arg in getattr(tp, "__args__", ()) or ():
            visit(arg)
        if hasattr(tp, "__metadata__"):
            visit(tp.__origin__)

    visit(root)
    return seen


@functools.cache
def _class_comments(cls: type) -> dict[str, str]:
    """Field name -> the ``#:`` lines above it, or else the comment beside it, in ``cls``'s source."""
    try:
        source = textwrap.dedent(inspect.getsource(cls))
    except (OSError, TypeError):
        return {}
    comments = {tok.start[0]: tok.string.lstrip("#").strip()
                for tok in tokenize.generate_tokens(io.StringIO(source).readline) if tok.type == tokenize.COMMENT}
    lines = source.splitlines()
    out = {}
    for node in ast.parse(source).body[0].body:
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)):
            continue
        above = []
        i = node.lineno  # (1-based: lines[i - 1] is line i)
        while i - 1 in comments and lines[i - 2].lstrip().startswith("#:"):
            above.insert(0, comments[i - 1].lstrip(":").strip())
            i -= 1
        text = " ".join(above) or comments.get(node.end_lineno, "")
        if text and not text.startswith("("):
            out[node.target.id] = text
        elif text:
            out[node.target.id] = text.strip("()")
    return out


def field_comments(model: type[BaseModel]) -> dict[str, str]:
    """The comments the models' source gives their fields, inherited ones included."""
    out: dict[str, str] = {}
    for cls in reversed(model.__mro__):
        if isinstance(cls, type) and issubclass(cls, BaseModel) and cls is not BaseModel:
            out.update(_class_comments(getattr(cls, "__pydantic_generic_metadata__", {}).get("origin") or cls))
    return out


def _add_units(node: Any, defs: dict, path: tuple[str, ...]) -> None:
    """Each property's unit (KEY_UNITS) as ``x-unit`` and at the end of its description."""
    from rbhyst.model.deck import KEY_UNITS

    for key, prop in _properties(node, defs):
        here = (*path, key)
        unit = _unit(KEY_UNITS, here)
        if unit and "x-unit" not in prop:  # (a table met again by another path has it)
            prop["x-unit"] = unit
            if unit != "signal":
                prop["description"] = (prop.get("description", "") + f" [{unit}]").strip()
        for child in _children(prop, defs):
            _add_units(child, defs, here)


def _unit(units: dict, path: tuple[str, ...]) -> str | None:
    for pattern, unit in units.items():
        if len(pattern) == len(path) and all(a in ("*", b) for a, b in zip(pattern, path)):
            return unit
    return None


def _properties(node: dict, defs: dict):
    node = _deref(node, defs)
    yield from node.get("properties", {}).items()


def _deref(node: dict, defs: dict) -> dict:
    while "$ref" in node:
        node = defs[node["$ref"].rsplit("/", 1)[1]]
    return node


def _children(prop: dict, defs: dict, named: bool = False) -> list[dict]:
    """The object schemas a property leads to: itself, its items, its union's members, a
    table's values (a name: "*" in KEY_UNITS), each once."""
    out = []
    prop = _deref(prop, defs)
    if "properties" in prop:
        out.append(prop)
    for alt in prop.get("anyOf", []) + prop.get("oneOf", []):
        out += _children(alt, defs)
    if isinstance(prop.get("items"), dict):
        out += _children(prop["items"], defs)
    if isinstance(prop.get("additionalProperties"), dict):
        out += [{"properties": {"*": prop["additionalProperties"]}}]
    return out
