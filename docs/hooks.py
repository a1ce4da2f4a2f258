"""MkDocs hook: the reference pages' generated parts, made from the code at every build so that
they cannot drift from it. A page holds a marker where a part goes:

- ``<!-- rbhyst:deck-keys -->``: every deck key, from the deck's JSON Schema (rbhyst.model.schema,
  itself from the pydantic models): type, unit, default, constraint and description;
- ``<!-- rbhyst:cli -->``: every command with its arguments and options, from the typer app.

The functions are plain (a test calls them without MkDocs).
"""

from __future__ import annotations

import json
import re

MARKERS = {"<!-- rbhyst:deck-keys -->": "deck_keys_markdown", "<!-- rbhyst:cli -->": "cli_markdown"}


def on_page_markdown(markdown, page, config, files):
    for marker, name in MARKERS.items():
        if marker in markdown:
            markdown = markdown.replace(marker, globals()[name]())
    return markdown


# ---------------------------------------------------------------- deck keys


def _deref(node: dict, defs: dict) -> tuple[dict, str | None]:
    name = None
    while "$ref" in node:
        name = node["$ref"].rsplit("/", 1)[1]
        node = defs[name]
    return node, name


def _anchor(name: str) -> str:
    return "table-" + name.lower().replace("_", "-")


def _type(prop: dict, defs: dict) -> str:
    """A property's type in words: number, a list of them, a table (linked), one of names."""
    if "$ref" in prop:
        _, name = _deref(prop, defs)
        return f"[{name}](#{_anchor(name)})"
    if "const" in prop:
        return f"`{json.dumps(prop['const'])}`"
    if "enum" in prop:
        return "one of " + ", ".join(f"`{json.dumps(v)}`" for v in prop["enum"])
    alts = [a for a in prop.get("anyOf", []) + prop.get("oneOf", []) if a.get("type") != "null"]
    if alts:
        return " or ".join(dict.fromkeys(_type(a, defs) for a in alts))
    kind = prop.get("type")
    if kind == "array":
        inner = _type(prop.get("items", {}), defs)
        return f"list of {inner}"
    if kind == "object":
        values = prop.get("additionalProperties")
        return f"table of {_type(values, defs)} by name" if isinstance(values, dict) else "table"
    return {"number": "number", "integer": "integer", "string": "string", "boolean": "true/false"}.get(kind, "any")


def _constraint(prop: dict) -> str:
    """The ranges and lengths a property (and its members) must keep."""
    out = []
    for node in [prop] + prop.get("anyOf", []) + prop.get("oneOf", []):
        for key, sign in (("exclusiveMinimum", ">"), ("minimum", ">="), ("exclusiveMaximum", "<"), ("maximum", "<=")):
            if key in node:
                out.append(f"{sign} {node[key]:g}")
        if "minItems" in node or "maxItems" in node:
            lo, hi = node.get("minItems"), node.get("maxItems")
            if lo == hi:
                out.append(f"{lo} items")
            elif hi is None:
                out.append(f"at least {lo} item{'s' if lo != 1 else ''}")
            else:
                out.append(f"{lo or 0} to {hi} items")
        if "minProperties" in node:
            out.append(f"at least {node['minProperties']} entr{'ies' if node['minProperties'] != 1 else 'y'}")
        items = node.get("items")
        if isinstance(items, dict) and "$ref" not in items:
            inner = _constraint(items)
            if inner:
                out.append(f"each {inner}")
    return "; ".join(dict.fromkeys(out))


def _default(prop: dict, required: bool) -> str:
    if required:
        return "required"
    if "default" not in prop or prop["default"] is None:
        return "-"
    if isinstance(prop["default"], dict):
        return "its keys' defaults"
    return f"`{json.dumps(prop['default'])}`"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _uses(schema: dict) -> dict[str, list[str]]:
    """Each table's places in a deck, as dotted keys ("[]": an entry of a list, "<name>": a key
    of your choosing)."""
    defs = schema["$defs"]
    places: dict[str, list[str]] = {}

    def visit(node: dict, path: str) -> None:
        node, name = _deref(node, defs)
        if name is not None:
            if path in places.setdefault(name, []):
                return
            places[name].append(path)
        for key, prop in node.get("properties", {}).items():
            for child, suffix in _reached(prop, defs):
                visit(child, f"{path}.{key}{suffix}" if path else f"{key}{suffix}")

    visit(schema, "")
    return places


def _reached(prop: dict, defs: dict) -> list[tuple[dict, str]]:
    out = []
    if "$ref" in prop:
        out.append((prop, ""))
    for alt in prop.get("anyOf", []) + prop.get("oneOf", []):
        out += _reached(alt, defs)
    if isinstance(prop.get("items"), dict):
        out += [(c, "[]" + s) for c, s in _reached(prop["items"], defs)]
    if isinstance(prop.get("additionalProperties"), dict):
        out += [(c, ".<name>" + s) for c, s in _reached(prop["additionalProperties"], defs)]
    return out


def deck_key_tables() -> list[tuple[str, list[str], str, list[list[str]]]]:
    """(table name, its places, its description, rows of key/type/unit/default/constraint/what)."""
    from rbhyst.model.schema import deck_schema

    schema = deck_schema()
    defs = schema["$defs"]
    places = _uses(schema)
    order = ["(top level)"] + [name for name in places if name in defs]
    out = []
    for name in order:
        node = schema if name == "(top level)" else defs[name]
        required = set(node.get("required", []))
        rows = []
        for key, prop in node.get("properties", {}).items():
            unit = prop.get("x-unit", "")
            unit = "the signal's `units`" if unit == "signal" else unit
            what = re.sub(r"\s*\[[^\]]*\]$", "", prop.get("description", ""))  # (the unit has its column)
            rows.append([f"`{key}`", _type(prop, defs), unit, _default(prop, key in required), _constraint(prop), what])
        where = ["(the deck itself)"] if name == "(top level)" else places.get(name, [])
        out.append((name, where, node.get("description", "") if name != "(top level)" else "", rows))
    return out


def deck_keys_markdown() -> str:
    parts = []
    for name, where, about, rows in deck_key_tables():
        title = "The deck's top level" if name == "(top level)" else f"{where[0] if where else name} ({name})"
        parts.append(f'### {title} {{#{_anchor(name) if name != "(top level)" else "table-top-level"}}}\n')
        parts.append("At: " + ", ".join(f"`{w}`" for w in where) + "\n")
        if about:
            parts.append(_cell(about) + "\n")
        parts.append("| key | type | unit | default | constraint | what it is |\n|---|---|---|---|---|---|")
        parts += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
        parts.append("")
    return "\n".join(parts)


# ---------------------------------------------------------------- command line


def cli_commands():
    """(name, click command) of every rbhyst command, in the order ``rbhyst --help`` lists them."""
    import typer

    from rbhyst.cli import app

    group = typer.main.get_command(app)
    return [(name, group.commands[name]) for name in group.list_commands(None)]


def cli_markdown() -> str:
    parts = []
    for name, cmd in cli_commands():
        ctx = cmd.make_context(f"rbhyst {name}", [], resilient_parsing=True)
        parts.append(f"### rbhyst {name}\n")
        usage = re.sub(r"\{(\w+)\}", lambda m: m.group(1).upper(), cmd.get_usage(ctx).replace("Usage: ", ""))
        parts.append("```text\n" + usage + "\n```\n")
        if cmd.help:
            parts.append(_plain(cmd.help) + "\n")
        rows = []
        for param in cmd.params:
            record = param.get_help_record(ctx)  # what --help prints: the names and metavar, the help
            if record is None:
                continue
            names, help_text = record
            kind = "argument" if param.param_type_name == "argument" else "option"
            rows.append([f"`{names}`", kind + (", required" if param.required else ""), help_text or ""])
        if rows:
            parts.append("| argument or option | kind | what it does |\n|---|---|---|")
            parts += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
        parts.append("")
    return "\n".join(parts)


def _plain(text: str) -> str:
    """A command's docstring as Markdown: paragraphs kept, "Long because ..." (for the code) left out."""
    paras = [p.strip() for p in text.split("\n\n") if p.strip()]
    return "\n\n".join(p for p in paras if not p.startswith("Long because"))
