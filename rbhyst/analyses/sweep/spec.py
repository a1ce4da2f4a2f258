"""The sweep file: pydantic models (strict, unknown keys forbidden) and ``read_spec``.

A sweep file is TOML or YAML, like a deck, and its mistakes are reported the same way: one
line per problem naming the key, list indices from 1.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, field_validator, model_validator

from rbhyst.model.deck import AccelUnits, PosFloat, Support, _key_problems, _messages, _Model, read_mapping
from rbhyst.errors import InputError

Name = Annotated[str, Field(min_length=1, pattern=r"^[^\x00-\x1f\x7f]+$")]


class Motion(Support):
    """One support motion: it replaces the deck's ``excitation.support`` (x1, x2 as there, and x3
    for a deck in space)."""

    name: Name

    @model_validator(mode="after")
    def _some_component(self):
        if self.x1 is None and self.x2 is None and self.x3 is None:
            raise ValueError("give x1, x2 or both (and x3 for a deck in space: signals as in the deck's "
                             "excitation.support)")
        return self


class MotionFolder(_Model):
    """Every record of a folder whose name matches ``x1`` (one ``*``), paired with the file
    matching ``x2`` (and ``x3``, for a deck in space) where the ``*`` stands for the same text;
    that text names the motion."""

    folder: str
    x1: str | None = None
    x2: str | None = None
    x3: str | None = None  # for a deck in space
    units: AccelUnits
    scale: float = 1.0
    dt: PosFloat | None = None

    @field_validator("x1", "x2", "x3")
    @classmethod
    def _one_star(cls, v: str | None) -> str | None:
        if v is None:
            return v
        if v.count("*") != 1:
            raise ValueError(f"{v!r}: a file name pattern with exactly one '*' (the motion's name)")
        if "/" in v or "\\" in v or any(c in v for c in "?[]"):
            raise ValueError(f"{v!r}: a file name in the folder, with '*' as its only wildcard")
        return v

    @model_validator(mode="after")
    def _some_component(self):
        if self.x1 is None and self.x2 is None and self.x3 is None:
            raise ValueError("give the pattern of x1, x2 or both (and x3 for a deck in space)")
        return self


Levels = Annotated[list[PosFloat], Field(min_length=1)]


class Scale(_Model):
    """The intensity axis: plain factors on every motion, or target peak ground accelerations."""

    factors: Levels | None = None
    pga_g: Levels | None = None

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("factors", "pga_g") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of `factors` or `pga_g`")
        levels = getattr(self, given[0])
        if len(set(levels)) != len(levels):
            raise ValueError(f"{given[0]}: a level is repeated")
        return self

    @property
    def kind(self) -> str:
        return "factors" if self.factors is not None else "pga_g"

    @property
    def levels(self) -> list[float]:
        return list(self.factors if self.factors is not None else self.pga_g)


class CaseSpec(_Model):
    """One explicit combination: deck values by dotted key, for one motion and scale level or all."""

    motion: Name | None = None
    scale: PosFloat | None = None
    values: dict[str, Any] = {}

    @field_validator("values", mode="before")
    @classmethod
    def _flat(cls, v):
        return flatten(v, leaf=lambda x: not isinstance(x, dict)) if isinstance(v, dict) else v


class LimitState(_Model):
    """A limit state: a case exceeds it when ``quantity`` (a cases.csv column, or + - * / max min
    abs of them and numbers) reaches ``limit``."""

    name: Name
    quantity: Annotated[str, Field(min_length=1, max_length=500)]  # (parsed with the columns it names)
    limit: float


class FragilityOptions(_Model):
    """How the fragility curves are fitted: the intensity measure and the bootstrap."""

    intensity: Literal["scale", "pga_g", "sa_g"] = "scale"
    period_s: PosFloat | None = None  # Sa's period (intensity = "sa_g")
    damping: Annotated[float, Field(ge=0, lt=1)] = 0.05  # Sa's damping ratio
    confidence: Annotated[float, Field(gt=0, lt=1)] = 0.9
    bootstrap: Annotated[int, Field(ge=0, le=100_000)] = 1000
    seed: Annotated[int, Field(ge=0)] = 1

    @model_validator(mode="after")
    def _period(self):
        if self.intensity == "sa_g" and self.period_s is None:
            raise _key_problems([("period_s", "required with intensity = \"sa_g\" (the period of Sa, s)")])
        if self.intensity != "sa_g" and self.period_s is not None:
            raise _key_problems([("period_s", f"goes with intensity = \"sa_g\", not {self.intensity!r}")])
        return self


class Cluster(_Model):
    """Where the cases run instead of local workers: a Dask scheduler, and the files of its TLS
    (the CA's certificate, this client's certificate and key; relative to the sweep file)."""

    scheduler: Name | None = None
    tls_ca_file: Name | None = None
    tls_cert: Name | None = None
    tls_key: Name | None = None

    def resolved(self, here: Path) -> "Cluster":
        """The same, with the files' paths absolute (relative ones against ``here``)."""
        return self.model_copy(update={k: str(here / v) for k in TLS_KEYS if (v := getattr(self, k)) is not None})


TLS_KEYS = ("tls_ca_file", "tls_cert", "tls_key")


class SweepSpec(_Model):
    deck: str
    motions: Annotated[list[Motion], Field(min_length=1)] | None = None
    motion_folders: Annotated[list[MotionFolder], Field(min_length=1)] | None = None
    scale: Scale | None = None
    vary: dict[str, Annotated[list[Any], Field(min_length=1)]] | None = None
    cases: Annotated[list[CaseSpec], Field(min_length=1)] | None = None
    limit_states: Annotated[list[LimitState], Field(min_length=1)] | None = None
    fragility: FragilityOptions | None = None


    cluster: Cluster | None = None

    @field_validator("vary", mode="before")
    @classmethod
    def _flat(cls, v):
        # `body.mass = [...]` unquoted in TOML is a nested table: the same key as "body.mass"
        return flatten(v, leaf=lambda x: not isinstance(x, dict)) if isinstance(v, dict) else v

    @field_validator("vary")
    @classmethod
    def _distinct(cls, v):
        if v is None:
            return v
        for key, values in v.items():
            seen: set = set()  # the hashable values, as same_value tells them apart
            others: list = []  # lists and tables: compared one by one
            for x in values:
                ident = value_identity(x)
                if ident in seen if ident is not None else any(same_value(x, y) for y in others):
                    raise ValueError(f"{key!r}: the value {x!r} is repeated")
                if ident is not None:
                    seen.add(ident)
                else:
                    others.append(x)
        return v

    @model_validator(mode="after")
    def _vary_or_cases(self):
        if self.vary is not None and self.cases is not None:
            raise ValueError("give `vary` (every combination) or `cases` (the combinations listed), not both")
        if self.fragility is not None and self.limit_states is None:
            raise _key_problems([("fragility", "give [[limit_states]] (name, quantity, limit) to fit curves to")])
        return self


def flatten(data: dict, leaf, prefix: str = "") -> dict:
    """{"body": {"mass": [1]}} -> {"body.mass": [1]}: nested tables become dotted keys."""
    out = {}
    for k, v in data.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict) and not leaf(v) and v:
            out.update(flatten(v, leaf, key))
        else:
            out[key] = v
    return out


def same_value(a, b) -> bool:
    """Equal and of the same kind (700 and 700.0 are both numbers, True is not 1)."""
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))
    return type(a) is type(b) and a == b


def value_identity(x):
    """What same_value compares of a hashable value, as a hashable key (two values are the same
    value exactly when their keys are equal); None for a value that cannot be hashed (a list, a
    table). A set of these finds a repeated value among thousands at once, where comparing every
    pair took half a minute for 10,000."""
    if isinstance(x, bool):
        return ("bool", x)
    if isinstance(x, (int, float)):
        return ("nan",) if isinstance(x, float) and math.isnan(x) else ("number", x)
    try:
        hash(x)
    except TypeError:
        return None
    return (type(x), x)


def read_spec(path: Path) -> SweepSpec:
    """Read and validate a sweep file (TOML or YAML)."""
    data = read_mapping(Path(path))
    if not isinstance(data, dict):
        raise InputError("(sweep): the top level must be a table of keys")
    try:
        return SweepSpec.model_validate(data)
    except ValidationError as err:
        raise InputError([line.replace("(deck)", "(sweep)") for line in _messages(err)]) from None
