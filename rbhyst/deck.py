"""The input deck: pydantic models (unknown keys forbidden) and ``load_deck``.

A deck is TOML or YAML with the same structure. Validation errors become
:class:`~rbhyst.errors.InputError` with one line per problem, each naming the
deck location (list indices count from 1, as vertices and elements do in the
seed and in the CSV columns).
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Annotated, Any, Generic, Literal, TypeVar, Union

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, ValidationError, field_validator, model_validator

from .errors import InputError
from .textfiles import read_text
from .hysteresis import limiting_curve, limiting_slope, parameter_set, reversal_stiffness

PosFloat = Annotated[float, Field(gt=0)]
Point = Annotated[list[float], Field(min_length=2, max_length=2)]

ACCEL_UNITS = {"g": 9.80665, "m/s2": 1.0, "cm/s2": 0.01}
FORCE_UNITS = {"N": 1.0, "kN": 1e3}
MOMENT_UNITS = {"N m": 1.0, "kN m": 1e3}

AccelUnits = Literal["g", "m/s2", "cm/s2"]
ForceUnits = Literal["N", "kN"]
MomentUnits = Literal["N m", "kN m"]
U = TypeVar("U")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


# ---------------------------------------------------------------- hysteresis


class Branch(_Model):
    """Eight VRM parameters of one branch (seed eqs. 14-15)."""

    kb: float
    f0: float
    alpha: PosFloat
    beta1: float = 0.0
    beta2: float = 0.0
    gamma1: float = 0.0
    gamma2: float = 0.0
    gamma3: float = 0.0


class HysteresisSet(_Model):
    """A named VRM set: ``loading`` applies for s > 0, ``unloading`` for s < 0."""

    loading: Branch
    unloading: Branch

    @model_validator(mode="after")
    def _curves_ordered(self):
        p = self.array()
        with np.errstate(over="ignore", invalid="ignore"):
            k = reversal_stiffness(p, 0.0)
            slopes = [float(limiting_slope(p, s, 0.0)) for s in (1, -1)]
        # no support is stiffer than 1e100 N/m; beyond it sums of stiffnesses may overflow
        if not all(abs(x) < 1e100 for x in (k, *slopes)):
            raise ValueError(f"the stiffness at u = 0 ({max(abs(k), *map(abs, slopes)):.3g}) is far out of "
                             "any physical range")
        gap = float(limiting_curve(p, 1, 0.0) - limiting_curve(p, -1, 0.0))
        if not gap >= 0.0:
            raise ValueError(
                f"the limiting curves cross at u = 0: c+(0) - c-(0) = {gap:.6g} must be >= 0 "
                "(with equal other parameters: f0 of loading + f0 of unloading >= 0; "
                "equal curves make a nonlinear elastic element)"
            )
        return self

    def array(self) -> np.ndarray:
        return parameter_set(self.loading.model_dump(), self.unloading.model_dump())


# ---------------------------------------------------------------- body and elements


class Body(_Model):
    vertices: Annotated[list[Point], Field(min_length=3)]
    mass: PosFloat


class Element(_Model):
    vertex: Annotated[int, Field(ge=1)] | None = None
    point: Point | None = None
    angle_deg: float
    hysteresis: str
    count: Annotated[int, Field(ge=1)] = 1

    @model_validator(mode="after")
    def _one_place(self):
        if (self.vertex is None) == (self.point is None):
            raise ValueError("give exactly one of `vertex` (1-based index) or `point` ([x1, x2] in m)")
        return self


# ---------------------------------------------------------------- excitation


class Record(_Model, Generic[U]):
    """A history read from a file: PEER .AT2, two columns time,value, or one column with ``dt``."""

    type: Literal["record"] = "record"
    file: str
    units: U
    scale: float = 1.0
    dt: PosFloat | None = None


class Sine(_Model, Generic[U]):
    """amplitude * sin(2 pi f t + phase), from t = start for ``cycles`` cycles (default: all)."""

    type: Literal["sine"]
    amplitude: float
    frequency_hz: PosFloat
    units: U
    phase_deg: float = 0.0
    start: Annotated[float, Field(ge=0)] = 0.0
    cycles: PosFloat | None = None


def _signal_kind(v: Any) -> str:
    return v.get("type", "record") if isinstance(v, dict) else getattr(v, "type", "record")


def _signal(units):
    return Annotated[
        Union[Annotated[Record[units], Tag("record")], Annotated[Sine[units], Tag("sine")]],
        Discriminator(_signal_kind),
    ]


class Support(_Model):
    x1: _signal(AccelUnits) | None = None
    x2: _signal(AccelUnits) | None = None


class Force(_Model):
    point: Point = [0.0, 0.0]
    p1: _signal(ForceUnits) | None = None
    p2: _signal(ForceUnits) | None = None
    m3: _signal(MomentUnits) | None = None


class Excitation(_Model):
    support: Support | None = None
    force: Force | None = None


# ---------------------------------------------------------------- analysis and output


class Analysis(_Model):
    dt: PosFloat
    duration: PosFloat | None = None
    integrator: str = "chang"
    #: accuracy limit on the stiffest instantaneous mode: omega_max * h (see README)
    max_omega_dt: PosFloat = 0.5
    #: at most 2**max_substep_level substeps per step before the run stops
    max_substep_level: Annotated[int, Field(ge=0, le=20)] = 12

    @field_validator("integrator")
    @classmethod
    def _known(cls, v: str) -> str:
        from .integrators import names

        if v not in names():
            raise ValueError(f"unknown integrator {v!r}; choose one of {', '.join(names())}")
        return v


class Output(_Model):
    directory: str | None = None
    plots: bool = True
    every: Annotated[int, Field(ge=1)] = 1


class Loops(_Model):
    """Imposed-displacement protocol for ``rbhyst calibrate-plot`` (default: the seed's Fig. 2)."""

    amplitude: PosFloat | Annotated[list[PosFloat], Field(min_length=1)] = 1.5
    frequency_hz: PosFloat = 1.0
    cycles: Annotated[int, Field(ge=1)] = 2
    points_per_cycle: Annotated[int, Field(ge=8)] = 2000


class Deck(_Model):
    title: str | None = None
    body: Body | None = None
    hysteresis: Annotated[dict[str, HysteresisSet], Field(min_length=1)]
    elements: Annotated[list[Element], Field(min_length=1)] | None = None
    excitation: Excitation | None = None
    analysis: Analysis | None = None
    output: Output = Output()
    loops: Loops | None = None


def cross_references(deck: Deck) -> list[str]:
    """Problems that span sections: undefined sets, vertex indices out of range."""
    problems = []
    for k, el in enumerate(deck.elements or [], start=1):
        if el.hysteresis not in deck.hysteresis:
            problems.append(
                f"elements[{k}].hysteresis: undefined set {el.hysteresis!r}; "
                f"defined: {', '.join(sorted(deck.hysteresis))}"
            )
        if el.vertex is not None and deck.body is not None and el.vertex > len(deck.body.vertices):
            problems.append(
                f"elements[{k}].vertex: {el.vertex} is out of range: the body has "
                f"{len(deck.body.vertices)} vertices"
            )
    return problems


def check_runnable(deck: Deck) -> None:
    """``rbhyst run`` needs a body, elements and an analysis section; loops do not."""
    missing = [f"{key}: required for an analysis" for key in ("body", "elements", "analysis")
               if getattr(deck, key) is None]
    if missing:
        raise InputError(missing)
    a = deck.analysis
    if a.duration is not None and a.dt > a.duration:
        raise InputError(f"analysis.dt: {a.dt} s is larger than analysis.duration = {a.duration} s")
    if deck.excitation is None or (deck.excitation.support is None and deck.excitation.force is None):
        if a.duration is None:
            raise InputError("analysis.duration: required when there is no excitation to take it from")


# ---------------------------------------------------------------- loading


class _YamlLoader(yaml.SafeLoader):
    """Safe loading (no object tags) with YAML 1.2 floats, so ``1e-3`` is a number as in TOML."""


_YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
        |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
        |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        re.X,
    ),
    list("-+0123456789."),
)


def _format_loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part + 1}]"
        elif part in ("record", "sine") or str(part).startswith(("Record[", "Sine[")):
            continue  # the union's tag is noise to a user
        elif re.fullmatch(r"[A-Za-z0-9_\-]+", str(part)):
            out += ("." if out else "") + str(part)
        else:  # a key with spaces or control characters: quoted, so the message stays one line
            out += f"[{str(part)!r}]"
    return out or "(deck)"


def _messages(err: ValidationError) -> list[str]:
    lines = []
    for e in err.errors():
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        if e["type"] == "extra_forbidden":
            msg = "unknown key"
        elif e["type"] == "missing":
            msg = "required key is missing"
        elif e["type"] == "union_tag_invalid":
            msg = (f"unknown type {e['ctx']['tag']!r}: use type = \"sine\", or give `file` "
                   "(and no type) for a record")
        lines.append(f"{_format_loc(e['loc'])}: {msg}")
    return list(dict.fromkeys(lines))


def parse_deck(data: Any) -> Deck:
    """Validate a parsed mapping; raise InputError with one line per problem."""
    if not isinstance(data, dict):
        raise InputError("(deck): the top level must be a table of keys")
    try:
        deck = Deck.model_validate(data)
    except ValidationError as err:
        raise InputError(_messages(err)) from None
    problems = cross_references(deck)
    if problems:
        raise InputError(problems)
    return deck


def read_mapping(path: Path) -> dict:
    """Parse a TOML (.toml) or YAML (.yaml/.yml) file into a mapping."""
    text = read_text(path)
    suffix = path.suffix.lower()
    if suffix == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"{path}: TOML syntax error: {exc}") from None
    if suffix in (".yaml", ".yml"):
        try:
            data = yaml.load(text, Loader=_YamlLoader)
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark
            where = f" (at line {mark.line + 1}, column {mark.column + 1})" if mark else ""
            raise InputError(f"{path}: YAML error: {exc.problem}{where}") from None
        except yaml.YAMLError as exc:
            raise InputError(f"{path}: YAML error: {exc}") from None
        return data if data is not None else {}
    raise InputError(f"{path}: unknown deck format {suffix!r}; use .toml, .yaml or .yml")


def load_deck(path: str | Path) -> Deck:
    """Read and validate a deck file."""
    return parse_deck(read_mapping(Path(path)))

