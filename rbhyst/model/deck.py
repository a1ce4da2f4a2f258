"""The input deck: pydantic models (unknown keys forbidden) and ``load_deck``.

A deck is TOML or YAML with the same structure. Validation errors become
:class:`~rbhyst.errors.InputError` with one line per problem, each naming the
deck location (list indices count from 1, as vertices and elements do in the
seed and in the CSV columns).
"""


import functools
import math
import re
import tomllib
from pathlib import Path
from typing import Annotated, Any, Generic, Literal, TypeVar, Union

import numpy as np
from pydantic import (BaseModel, ConfigDict, Discriminator, Field, PrivateAttr, Tag, ValidationError, field_validator,
                      model_validator)
from pydantic_core import PydanticCustomError

from rbhyst.errors import InputError
from rbhyst.model.integrators import INTEGRATORS
from rbhyst.model.periods import default_periods
from rbhyst.files.textfiles import read_text
from rbhyst.model.hysteresis import PARAMS, limiting_curve, limiting_slope, reversal_stiffness

PosFloat = Annotated[float, Field(gt=0)]
#: a point: [x1, x2] in a plane deck, [x1, x2, x3] in a deck in space (the body's vertices
#: decide which: :func:`dimension_problems`)
Point = Annotated[list[float], Field(min_length=2, max_length=3)]

ACCEL_UNITS = {"g": 9.80665, "m/s2": 1.0, "cm/s2": 0.01}
FORCE_UNITS = {"N": 1.0, "kN": 1e3}
MOMENT_UNITS = {"N m": 1.0, "kN m": 1e3}

AccelUnits = Literal["g", "m/s2", "cm/s2"]
ForceUnits = Literal["N", "kN"]
MomentUnits = Literal["N m", "kN m"]
U = TypeVar("U")


class _Model(BaseModel):
    # (validators built at first use, not at import: a command imports every model and validates
    # with one, the deck; 5 ms of its start)
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True, defer_build=True)


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
        problem = _curves_problem(self.parameters())
        if problem is not None:
            raise ValueError(problem)
        return self

    def parameters(self) -> tuple[float, ...]:
        """The sixteen numbers, loading's then unloading's, in the order of hysteresis.PARAMS."""
        return tuple(getattr(b, name) for b in (self.loading, self.unloading) for name in PARAMS)

    def array(self) -> np.ndarray:
        """The ``(2, 8)`` parameter array (hysteresis.parameter_set)."""
        return np.array(self.parameters(), dtype=float).reshape(2, len(PARAMS))


@functools.lru_cache(maxsize=256)
def _curves_problem(params: tuple[float, ...]) -> str | None:
    """What is wrong with a set's curves at u = 0, or None. Of its numbers alone: worked out once
    per process for each set (a sweep validates the same sets for each of its cases, two of
    them a tenth of the time it took to build 10,000 cases)."""
    p = np.array(params, dtype=float).reshape(2, len(PARAMS))
    with np.errstate(over="ignore", invalid="ignore"):
        k = reversal_stiffness(p, 0.0)
        slopes = [float(limiting_slope(p, s, 0.0)) for s in (1, -1)]
    # no support is stiffer than 1e100 N/m; beyond it sums of stiffnesses may overflow
    if not all(abs(x) < 1e100 for x in (k, *slopes)):
        return f"the stiffness at u = 0 ({max(abs(k), *map(abs, slopes)):.3g}) is far out of any physical range"
    gap = float(limiting_curve(p, 1, 0.0) - limiting_curve(p, -1, 0.0))
    if not gap >= 0.0:
        return (f"the limiting curves cross at u = 0: c+(0) - c-(0) = {gap:.6g} must be >= 0 "
                "(with equal other parameters: f0 of loading + f0 of unloading >= 0; "
                "equal curves make a nonlinear elastic element)")
    return None


# ---------------------------------------------------------------- body and elements


def _key_problems(problems: list[tuple[str, str]]) -> PydanticCustomError:
    """Problems with named keys of a table, raised from its model validator: one line per key."""
    return PydanticCustomError("deck_keys", "; ".join(f"{k}: {m}" for k, m in problems),
                               {"problems": tuple(problems)})


Vertices = Annotated[list[Point], Field(min_length=3)]


class Box(_Model):
    """A rectangular box in space: its edges along x1, x2, x3 (m) and its centre (deck frame)."""

    size: Annotated[list[PosFloat], Field(min_length=3, max_length=3)]
    centre: Annotated[list[float], Field(min_length=3, max_length=3)] = [0.0, 0.0, 0.0]


class Part(_Model):
    """One uniform polygon of a body of several parts (seed eqs. 1-4 each), or in space one
    uniform convex polyhedron (the hull of ``vertices``) or ``box``."""

    vertices: Vertices | None = None
    box: Box | None = None
    mass: PosFloat

    @model_validator(mode="after")
    def _one_shape(self):
        if (self.vertices is None) == (self.box is None):
            raise ValueError("give exactly one of `vertices` or `box` (a box in space)")
        return self


#: the standard acceleration of gravity (m/s2) and how far a deck's may differ from it (the Earth's
#: ranges over 9.78-9.83 m/s2; 5 % allows a rounded 9.5 or 10): beyond, body.gravity_check = false
STANDARD_GRAVITY = 9.80665
GRAVITY_SPREAD = 0.05


def _gravity_units(g: float) -> str:
    """The units a gravity of magnitude g (read as m/s2) was most likely given in."""
    ratios = {"mm/s2": 1e-3, "cm/s2": 1e-2, "g (1 for 9.81 m/s2)": STANDARD_GRAVITY, "ft/s2": 0.3048,
              "in/s2": 0.0254}
    return min(ratios, key=lambda u: abs(np.log(g * ratios[u] / STANDARD_GRAVITY)))


class Body(_Model):
    """Exactly one of three forms: ``vertices`` + ``mass`` (one uniform polygon), ``parts``
    (several uniform polygons, which may overlap), or ``mass`` + ``mass_centre`` + ``inertia``
    (about the mass centre) + ``vertices`` (the outline, for drawing and vertex references)."""

    vertices: Vertices | None = None
    #: in space, a rectangular box instead of ``vertices``
    box: Box | None = None
    mass: PosFloat | None = None
    parts: Annotated[list[Part], Field(min_length=1)] | None = None
    mass_centre: Point | None = None
    #: J_x3 about the mass centre (kg m2) in the plane; in space the 3 x 3 tensor about it
    inertia: float | list[list[float]] | None = None
    #: the acceleration of gravity in the deck's frame (m/s2): the weight m g acts at G and the
    #: run starts from the static equilibrium under it (see the documentation, "Gravity preload")
    gravity: Point | None = None
    #: false: a gravity of any magnitude (another planet, a centrifuge); true: |gravity| within
    #: GRAVITY_SPREAD of the standard 9.80665 m/s2 (or zero), else a mistake of units
    gravity_check: bool = True

    @field_validator("inertia", mode="before")
    @classmethod
    def _inertia(cls, v):
        """A positive number (the plane's J_x3) or a 3 x 3 table of numbers (in space: whether it is
        symmetric positive definite is rbhyst.model.solid's to say, with its numbers)."""
        if _number(v):
            if not (v > 0 and np.isfinite(v)):
                raise ValueError("must be greater than 0")
            return float(v)
        if (isinstance(v, list) and len(v) == 3 and all(isinstance(r, list) and len(r) == 3 for r in v)
                and all(_number(x) and np.isfinite(x) for r in v for x in r)):
            return [[float(x) for x in r] for r in v]
        raise ValueError(f"{v!r} must be a positive number (J_x3 about the mass centre, kg m2, in the plane) or "
                         "the 3 x 3 tensor about it (in space)")

    @model_validator(mode="after")
    def _one_form(self):
        given = [k for k in ("vertices", "box", "mass", "mass_centre", "inertia") if getattr(self, k) is not None]
        problems = []
        if self.parts is not None:
            why = {"vertices": "the parts' vertices are the outline", "mass": "each part has its own mass",
                   "mass_centre": "the parts give the mass centre", "inertia": "the parts give the inertia",
                   "box": "each part has its own shape"}
            problems = [(k, f"not with body.parts: {why[k]}") for k in given]
        elif "box" in given:
            problems = [(k, "not with body.box: the box is the body's shape (its properties follow from it)")
                        for k in ("vertices", "mass_centre", "inertia") if k in given]
            problems += [(k, "required key is missing") for k in ("mass",) if k not in given]
        else:
            problems = [(k, "required key is missing") for k in ("vertices", "mass") if k not in given]
            direct = ("mass_centre", "inertia")
            if any(k in given for k in direct):
                problems += [(k, f"required with body.{other}: a body given by its properties needs mass, "
                                 "mass_centre, inertia (about the mass centre) and vertices (its outline)")
                             for k, other in (direct, direct[::-1]) if k not in given]
        g = float(np.linalg.norm(self.gravity)) if self.gravity is not None else 0.0
        if self.gravity_check and g > 0 and abs(g / STANDARD_GRAVITY - 1.0) > GRAVITY_SPREAD:
            problems.append(("gravity", f"|g| = {g:.6g} m/s2 is {g / STANDARD_GRAVITY:.4g} times the standard "
                                        f"{STANDARD_GRAVITY} m/s2: rbhyst takes it in m/s2 (was it given in "
                                        f"{_gravity_units(g)}?); body.gravity_check = false allows any magnitude"))
        if problems:
            raise _key_problems(problems)
        return self

    @property
    def form(self) -> Literal["polygon", "parts", "direct"]:
        if self.parts is not None:
            return "parts"
        return "polygon" if self.inertia is None else "direct"

    @property
    def dimensions(self) -> int:
        """3 for a body in space (a box, or vertices of three coordinates), else 2."""
        shapes = [(p.vertices, p.box) for p in self.parts] if self.parts is not None else [(self.vertices, self.box)]
        first_vertices, first_box = shapes[0]
        if first_box is not None:
            return 3
        return 3 if first_vertices and len(first_vertices[0]) == 3 else 2


class _Placed(_Model):
    """Something attached to the body at a vertex or a point, along an angle (in the plane) or a
    direction (in space: its line of action, any length but zero)."""

    part: Annotated[int, Field(ge=1)] | None = None
    vertex: Annotated[int, Field(ge=1)] | None = None
    point: Point | None = None
    angle_deg: float | None = None
    direction: Annotated[list[float], Field(min_length=3, max_length=3)] | None = None
    count: Annotated[int, Field(ge=1)] = 1

    @model_validator(mode="after")
    def _one_place(self):
        return _one_place(self)


def _one_place(entry):
    """An element, damper or isolator is at exactly one vertex or point; ``part`` names a vertex's part."""
    if (entry.vertex is None) == (entry.point is None):
        raise ValueError("give exactly one of `vertex` (1-based index) or `point` ([x1, x2] in m)")
    if entry.part is not None and entry.vertex is None:
        raise _key_problems([("part", "goes with `vertex` (that part's vertex); a `point` is in the "
                                      "deck's frame whichever part it lies on")])
    return entry


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _stroke_value(v):
    """An element's stroke: a positive number (symmetric) or [lower, upper] with lower < 0 < upper (m)."""
    what = "a positive number (m) or [lower, upper] with lower < 0 < upper (m)"
    if v is None:
        return v
    if _number(v):
        if not (v > 0 and np.isfinite(v)):
            raise ValueError(f"{v:g} must be {what}")
        return float(v)
    if isinstance(v, list) and len(v) == 2 and all(_number(x) and np.isfinite(x) for x in v):
        if not v[0] < 0.0 < v[1]:
            raise ValueError(f"[{v[0]:g}, {v[1]:g}] must be [lower, upper] with lower < 0 < upper (m)")
        return [float(x) for x in v]
    raise ValueError(f"{v!r} must be {what}")


class Stop(_Model):
    """A stop beyond a gap (rbhyst.model.stop: Walton and Braun's linear loading and unloading):
    ``gap`` symmetric (m), or [lower, upper] with lower < 0 < upper (the deformations where it is
    met), ``stiffness`` K (N/m) and ``restitution`` e (0 < e <= 1)."""

    #: where the stop is met: symmetric, or [lower, upper] with lower < 0 < upper (the element's deformation)
    gap: float | list[float]
    #: K: the loading stiffness (unloading K / restitution^2)
    stiffness: PosFloat
    #: e: the coefficient of restitution of an impact on it (0 < e <= 1)
    restitution: Annotated[float, Field(gt=0.0, le=1.0)]

    @field_validator("gap", mode="before")
    @classmethod
    def _gap(cls, v):
        return _stroke_value(v)

    @property
    def limits(self) -> tuple[float, float]:
        """(lower, upper): the deformations where the stop is met."""
        return (-self.gap, self.gap) if not isinstance(self.gap, list) else tuple(self.gap)

    @property
    def law(self) -> tuple[float, float, float, float]:
        """(lower, upper, K, e): an Element's ``stop`` (rbhyst.model.system.Element)."""
        return (*self.limits, float(self.stiffness), float(self.restitution))


class Element(_Placed):
    hysteresis: str
    #: the deformation it can take (m): symmetric, or [lower, upper] with lower < 0 < upper
    stroke: float | list[float] | None = None
    #: a stop beyond a gap: the mount bottoms out on it (rbhyst.model.stop)
    stop: Stop | None = None

    @field_validator("stroke", mode="before")
    @classmethod
    def _stroke(cls, v):
        return _stroke_value(v)

    @property
    def stroke_limits(self) -> tuple[float, float] | None:
        if self.stroke is None:
            return None
        return (-self.stroke, self.stroke) if not isinstance(self.stroke, list) else tuple(self.stroke)


class _ByDirection(_Model):
    """An isolator's sets or strokes by direction: ``axial`` and ``shear`` (both shear lines), or
    in space ``shear1`` and ``shear2`` separately."""

    @model_validator(mode="after")
    def _shear_once(self):
        if self.shear is not None:
            problems = [(k, "not with `shear` (that of both shear lines): give `shear`, or `shear1` and `shear2`")
                        for k in ("shear1", "shear2") if getattr(self, k) is not None]
            if problems:
                raise _key_problems(problems)
        return self


class IsolatorSets(_ByDirection):
    """The hysteresis set (a name of [hysteresis.<name>]) of each of an isolator's directions."""

    axial: str
    shear: str | None = None
    shear1: str | None = None
    shear2: str | None = None


class IsolatorStrokes(_ByDirection):
    """The stroke of each of an isolator's directions, as an element's (any may be left out)."""

    axial: float | list[float] | None = None
    shear: float | list[float] | None = None
    shear1: float | list[float] | None = None
    shear2: float | list[float] | None = None

    @field_validator("axial", "shear", "shear1", "shear2", mode="before")
    @classmethod
    def _stroke(cls, v):
        return _stroke_value(v)


class IsolatorStops(_ByDirection):
    """The stop of each of an isolator's directions, as an element's (any may be left out)."""

    axial: Stop | None = None
    shear: Stop | None = None
    shear1: Stop | None = None
    shear2: Stop | None = None


def _lines(v, what: str):
    """Shear lines as a deck gives them: lists of numbers, one line alone as it is (how many lines
    and components is checked with the deck's dimension, in rbhyst.model.isolators)."""
    if isinstance(v, list) and v and all(_number(x) for x in v):
        v = [v]
    if not (isinstance(v, list) and v and all(isinstance(s, list) and 1 <= len(s) <= 3 for s in v)
            and all(_number(x) and np.isfinite(x) for s in v for x in s)):
        raise ValueError(f"{v!r} must be {what}")
    return [[float(x) for x in s] for s in v]


class Isolator(_Model):
    """A mount with an axial and shear behaviour (a wire rope isolator) as one part with local
    axes, expanded into uncoupled uniaxial elements (rbhyst.model.isolators): in space ``axial``
    (its line, towards its support) and two ``shear`` lines (default: perpendicular to it, each
    nearest a deck axis); in the plane ``axial_deg`` and ``shear_deg`` (default axial_deg +- 90)."""

    part: Annotated[int, Field(ge=1)] | None = None
    vertex: Annotated[int, Field(ge=1)] | None = None
    point: Point | None = None
    axial: Annotated[list[float], Field(min_length=2, max_length=3)] | None = None
    shear: list[list[float]] | None = None
    axial_deg: float | None = None
    shear_deg: float | None = None
    hysteresis: IsolatorSets
    count: Annotated[int, Field(ge=1)] = 1
    stroke: IsolatorStrokes | None = None
    #: a stop beyond a gap for each direction (any may be left out)
    stop: IsolatorStops | None = None
    #: "mss": the two shear lines are one multiple shear spring (rbhyst.model.mss), in space
    coupling: Literal["none", "mss"] = "none"
    #: the MSS's springs (even, at least 4; rbhyst.model.mss.DEFAULT_SPRINGS without)
    springs: Annotated[int, Field(ge=4)] | None = None
    #: m: where the MSS's exponential term matches the set's (OpenSees' -lim)
    reference: PosFloat | None = None

    @field_validator("shear", mode="before")
    @classmethod
    def _shear(cls, v):
        return v if v is None else _lines(v, "two shear lines, [[d1, d2, d3], [d1, d2, d3]]")

    @field_validator("hysteresis", mode="before")
    @classmethod
    def _sets(cls, v):
        if isinstance(v, str):
            raise ValueError(f"{v!r}: an isolator takes a set for each direction: "
                             "{ axial = \"...\", shear = \"...\" } (or shear1 and shear2 in space)")
        return v

    @field_validator("stroke", mode="before")
    @classmethod
    def _strokes(cls, v):
        if v is not None and not isinstance(v, dict):
            raise ValueError(f"{v!r}: an isolator takes a stroke for each direction: "
                             "{ axial = 0.03, shear = [-0.05, 0.05] } (any may be left out)")
        return v

    @field_validator("stop", mode="before")
    @classmethod
    def _stops(cls, v):
        if v is not None and not (isinstance(v, dict) and set(v) <= {"axial", "shear", "shear1", "shear2"}):
            raise ValueError(f"{v!r}: an isolator takes a stop for each direction: {{ axial = {{ gap = 0.02, "
                             "stiffness = 1e6, restitution = 0.5 } } (axial, shear, shear1, shear2; any may be left out)")
        return v

    @model_validator(mode="after")
    def _one_place(self):
        return _one_place(self)


#: the hysteresis set of a contact's element: no VRM force of its own (kb = f0 = 0; alpha 1, any
#: positive value, so that its branches are well defined), its stop bears it
CONTACT_SET = "(contact)"


class Contact(_Model):
    """A point of the body resting on the ground along ``normal`` (from the ground towards the
    body): compression only, never tension, a stop of ``stiffness`` and ``restitution`` met
    once the point has moved ``gap`` (m, 0: touching at rest) against the normal
    (rbhyst.model.stop). Frictionless."""

    part: Annotated[int, Field(ge=1)] | None = None
    vertex: Annotated[int, Field(ge=1)] | None = None
    point: Point | None = None
    #: from the ground towards the body, any length but zero
    normal: Annotated[list[float], Field(min_length=2, max_length=3)]
    #: K: the contact's loading stiffness (unloading K / restitution^2)
    stiffness: PosFloat
    #: e: the coefficient of restitution of a landing (0 < e <= 1)
    restitution: Annotated[float, Field(gt=0.0, le=1.0)]
    #: how far above the ground the point is at rest (0: touching)
    gap: Annotated[float, Field(ge=0.0)] = 0.0
    #: identical contacts at the point
    count: Annotated[int, Field(ge=1)] = 1

    @model_validator(mode="before")
    @classmethod
    def _frictionless(cls, v):
        if isinstance(v, dict) and "friction" in v:
            raise _key_problems([("friction", "contacts are frictionless (a contact bears along its normal only); "
                                              "give the tangential restraint as [[elements]] or [[isolators]]")])
        return v

    @field_validator("normal")
    @classmethod
    def _normal(cls, v):
        if not all(np.isfinite(x) for x in v) or not any(x != 0.0 for x in v):
            raise ValueError(f"{v!r} must be a direction: numbers, not all zero")
        return v

    @model_validator(mode="after")
    def _one_place(self):
        return _one_place(self)

    def element(self, dimensions: int) -> "Element":
        """The element it is: along its normal, no VRM force (CONTACT_SET), a stop on the
        compression side at -gap and none on the other."""
        place = {k: getattr(self, k) for k in ("part", "vertex", "point") if getattr(self, k) is not None}
        if dimensions == 3:
            line = {"direction": [float(x) for x in self.normal]}
        else:
            line = {"angle_deg": math.degrees(math.atan2(self.normal[1], self.normal[0]))}
        stop = Stop.model_construct(gap=[-self.gap, math.inf], stiffness=self.stiffness, restitution=self.restitution)
        return Element.model_construct(**place, **line, hysteresis=CONTACT_SET, count=self.count, stroke=None,
                                       stop=stop)


class Damper(_Placed):
    """A linear viscous damper: force c times its rate of deformation along angle_deg (eqs. 5-8);
    c = 0 keeps its place and columns with no force (a sweep's no-damper baseline)."""

    c: Annotated[float, Field(ge=0)]  # N s/m


class Rayleigh(_Model):
    """C = a0 M + a1 K0 (K0 the initial system's stiffness, as summary.json's k0): the damping
    ``ratio`` at two frequencies, given in Hz or as two modes of (M, K0) counted from 1."""

    ratio: Annotated[float, Field(gt=0, lt=1)] | Annotated[list[Annotated[float, Field(gt=0, lt=1)]],
                                                           Field(min_length=2, max_length=2)]
    frequencies_hz: Annotated[list[PosFloat], Field(min_length=2, max_length=2)] | None = None
    #: (at most 3 in the plane: dimension_problems)
    modes: Annotated[list[Annotated[int, Field(ge=1, le=6)]], Field(min_length=2, max_length=2)] | None = None

    @model_validator(mode="after")
    def _two_points(self):
        given = [k for k in ("frequencies_hz", "modes") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of `frequencies_hz` ([f1, f2] in Hz) or `modes` ([i, j], "
                             "the initial system's modes counted from 1)")
        pair = getattr(self, given[0])
        if pair[0] == pair[1]:
            raise _key_problems([(given[0], f"{pair}: two different {'frequencies' if given[0][0] == 'f' else 'modes'}"
                                            " (one point does not fix a0 and a1)")])
        return self

    @property
    def ratios(self) -> tuple[float, float]:
        return tuple(self.ratio) if isinstance(self.ratio, list) else (self.ratio, self.ratio)


class Damping(_Model):
    """Damping beyond the elements' hysteresis and the dampers: Rayleigh's, optionally."""

    rayleigh: Rayleigh | None = None


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
    #: the amplitude rises smoothly from 0 over this many cycles (signals.ramp_envelope)
    ramp_cycles: Annotated[float, Field(ge=0)] = 0.0


PULSES = ("half-sine", "haversine", "terminal-peak-sawtooth", "triangle", "trapezoid")


class Pulse(_Model, Generic[U]):
    """A shock pulse of peak ``amplitude`` lasting ``duration`` s from ``start`` (MIL-DTL-901,
    MIL-STD-810 shapes): half-sine, haversine, terminal-peak sawtooth, symmetric triangle,
    trapezoid (rising and falling over ``rise`` s). ``compensation = "pre-post"``: half-sine
    pre- and post-pulses of the opposite sign, peaks ``compensation_ratio`` of the main one, that
    bring the table's velocity and displacement back to zero (rbhyst.model.shock_pulses); the
    pre-pulse then starts at ``start`` and the main pulse follows it."""

    type: Literal["half-sine", "haversine", "terminal-peak-sawtooth", "triangle", "trapezoid"]
    amplitude: float
    units: U
    duration: PosFloat
    start: Annotated[float, Field(ge=0)] = 0.0
    #: s, a trapezoid's rise and fall (default a tenth of its duration)
    rise: PosFloat | None = None
    compensation: Literal["none", "pre-post"] = "none"
    compensation_ratio: Annotated[float, Field(gt=0, le=0.2)] = 0.1

    @model_validator(mode="after")
    def _rise(self):
        if self.rise is not None and self.type != "trapezoid":
            raise ValueError(f"rise: only a trapezoid has one (this pulse is a {self.type})")
        if self.rise is not None and not self.rise < 0.5 * self.duration:
            raise ValueError(f"rise: {self.rise:g} s must be below half the duration ({0.5 * self.duration:g} s)")
        if "compensation_ratio" in self.model_fields_set and self.compensation == "none":
            raise ValueError("compensation_ratio: only with compensation = \"pre-post\"")
        return self


PSD_UNITS = Literal["g2/Hz", "(m/s2)2/Hz"]


class Random(_Model):
    """A stationary Gaussian support acceleration with a power spectral density: breakpoints
    [[frequency_hz, value], ...] (log-log between them, as MIL-STD-810 tables give them) or a CSV
    file of them; ``duration`` s long, the same history for the same ``seed`` (see
    rbhyst.model.random_vibration). ``dt``: its sample step (default a tenth of the period
    of the PSD's highest frequency); ``scale`` multiplies the history (the PSD by its square);
    ``ramp`` and ``clip_sigma`` as a controller starts, stops and limits it."""

    type: Literal["random"]
    psd: str | list[list[float]]
    units: PSD_UNITS
    duration: PosFloat
    seed: Annotated[int, Field(ge=0)]
    dt: PosFloat | None = None
    scale: float = 1.0
    #: s, the start-up and shut-down ramps (None: 2 s, at most a tenth of the duration; 0: none)
    ramp: Annotated[float, Field(ge=0)] | None = None
    #: the peaks limited to this many times the rms (a controller's sigma clipping; None: not)
    clip_sigma: Annotated[float, Field(ge=2)] | None = None

    @field_validator("psd", mode="before")
    @classmethod
    def _breakpoints(cls, v):
        if isinstance(v, list):
            from rbhyst.model.random_vibration import psd_problems

            problems = psd_problems(v)
            if problems and problems[0][0] is None:
                raise ValueError(problems[0][1])
            if problems:
                raise _key_problems(problems)
            return [[float(x) for x in p] for p in v]
        return v


def _signal_kind(v: Any) -> str:
    kind = v.get("type", "record") if isinstance(v, dict) else getattr(v, "type", "record")
    return "pulse" if kind in PULSES else kind


def _signal(units):
    return Annotated[
        Union[Annotated[Record[units], Tag("record")], Annotated[Sine[units], Tag("sine")],
              Annotated[Pulse[units], Tag("pulse")]],
        Discriminator(_signal_kind),
    ]


def _support_signal():
    """What a support acceleration may be: a signal of _signal, or random vibration."""
    return Annotated[
        Union[Annotated[Record[AccelUnits], Tag("record")], Annotated[Sine[AccelUnits], Tag("sine")],
              Annotated[Pulse[AccelUnits], Tag("pulse")], Annotated[Random, Tag("random")]],
        Discriminator(_signal_kind),
    ]


class PlaneSupport(_Model):
    """Support motion along x1 and x2 (a sweep's motions)."""

    x1: _support_signal() | None = None
    x2: _support_signal() | None = None


class Support(PlaneSupport):
    """A deck's support motion: along x1, x2 and, in space, x3."""

    x3: _support_signal() | None = None  # in space only


class Force(_Model):
    #: where p1 and p2 act, in the deck's frame; absent: at the mass centre G (said in a note)
    point: Point | None = None
    p1: _signal(ForceUnits) | None = None
    p2: _signal(ForceUnits) | None = None
    m3: _signal(MomentUnits) | None = None
    # in space only: the force along x3 and the moments about x1 and x2
    p3: _signal(ForceUnits) | None = None
    m1: _signal(MomentUnits) | None = None
    m2: _signal(MomentUnits) | None = None


class Excitation(_Model):
    support: Support | None = None
    force: Force | None = None


# ---------------------------------------------------------------- analysis and output


class Analysis(_Model):
    dt: PosFloat
    duration: PosFloat | None = None
    #: the method, named: exactly it at dt; left out, rbhyst chooses the method and the compute
    #: step that meet warn_error, with dt the output interval (see the documentation, "Accuracy by default")
    integrator: str | None = None
    #: accuracy limit on the stiffest instantaneous mode: omega_max * h (see the documentation, "Stiffness monitor")
    max_omega_dt: PosFloat = 0.5
    #: at most 2**max_substep_level substeps per step before the run stops
    max_substep_level: Annotated[int, Field(ge=0, le=20)] = 12
    #: the adaptive integrator's relative tolerance
    rtol: Annotated[float, Field(gt=1e-14, lt=1e-2)] = 1e-8
    #: the accuracy asked for: rbhyst chooses how to meet it (see the documentation, "Get the accuracy you need")
    tolerance: Annotated[float, Field(gt=0, lt=1)] | None = None
    #: a run whose estimated error exceeds this warns
    warn_error: Annotated[float, Field(gt=0, lt=1)] = 0.01
    #: estimate every run's error (false skips it: a sweep that has checked its dt once)
    estimate_error: bool = True
    #: the body's kinematics: the seed's small rotations (eqs. 7-8), exact rotations of any size,
    #: or "auto": small where the terms they neglect stay below a tenth of warn_error, else exact
    kinematics: Literal["auto", "small", "exact"] = "auto"

    @field_validator("integrator")
    @classmethod
    def _known(cls, v: str | None) -> str | None:
        if v is not None and v not in INTEGRATORS:
            raise ValueError(f"unknown integrator {v!r}; choose one of {', '.join(INTEGRATORS)}")
        return v


#: names a point may not take (case aside): G's own plots and spectra, the ground's spectra
RESERVED_POINT_NAMES = ("G", "ground", "x1", "x2", "theta3")
#: ... and in space (dimension_problems)
RESERVED_IN_SPACE = ("x3", "theta1", "theta2")
_POINT_NAME = re.compile(r"[A-Za-z0-9_]+")


class OutputPoint(_Model):
    """A point of interest on the body: its motion gets columns `<name>_u1_m`, ... (eqs. 7-8)."""

    name: str
    point: Point  # m, in the deck's frame

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not _POINT_NAME.fullmatch(v):
            raise ValueError(f"{v!r}: letters, digits and _ only (it names columns and files)")
        reserved = {r.lower(): r for r in RESERVED_POINT_NAMES}
        if v.lower() in reserved:
            raise ValueError(f"{v!r} is taken by rbhyst's own outputs ({', '.join(RESERVED_POINT_NAMES)}: "
                             "the mass centre's plots, the ground's spectra): choose another")
        return v


Ratio = Annotated[float, Field(ge=0, lt=1)]


class Spectra(_Model):
    """Response spectra of the ground, of G and of every point (see the documentation, "Points of
    interest and spectra"): ``kind = "sa"`` against period (spectra.csv), or ``"srs"``, the shock
    response spectrum against frequency in the terms of ISO 18431-4 (srs.csv)."""

    #: "sa": max |absolute acceleration| against period; "srs": maximax, positive and negative,
    #: primary and residual against frequency
    kind: Literal["sa", "srs"] = "sa"
    #: damping ratios of the oscillators (a number or a list; kind "sa")
    damping: Annotated[list[Ratio], Field(min_length=1)] = [0.05]
    #: s; default: 100 periods log-spaced from 0.01 to 10 s (kind "sa")
    periods_s: Annotated[list[PosFloat], Field(min_length=1)] | None = None
    #: quality factors Q = 1 / (2 damping) (a number or a list; kind "srs"; default 10)
    q: Annotated[list[Annotated[float, Field(gt=0.5)]], Field(min_length=1)] | None = None
    #: Hz, [lowest, highest] (kind "srs"; default 1 Hz to the lesser of 10 kHz and a tenth of 1 / analysis.dt)
    range_hz: Annotated[list[PosFloat], Field(min_length=2, max_length=2)] | None = None
    #: frequencies an octave over range_hz (kind "srs"; default 12)
    per_octave: Annotated[int, Field(ge=1)] | None = None

    @field_validator("q", mode="before")
    @classmethod
    def _one_q_is_a_list(cls, v):
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else v

    @field_validator("q")
    @classmethod
    def _distinct_qs(cls, v):
        if v is not None and len(set(v)) != len(v):
            raise ValueError(f"{v}: each Q once")
        return v

    @field_validator("range_hz")
    @classmethod
    def _ascending(cls, v):
        if v is not None and not v[1] > v[0]:
            raise ValueError(f"{v}: [lowest, highest] Hz, the lower first")
        return v

    @model_validator(mode="after")
    def _keys_of_the_kind(self):
        other = (("q", "range_hz", "per_octave") if self.kind == "sa" else ("damping", "periods_s"))
        wrong = [k for k in other if k in self.model_fields_set]
        if wrong:
            raise ValueError(f"{', '.join(wrong)}: not with kind = {self.kind!r} "
                             + ("(q, range_hz and per_octave are the shock spectrum's: kind = \"srs\")"
                                if self.kind == "sa" else "(a shock spectrum takes q, range_hz and per_octave)"))
        return self

    @property
    def qs(self) -> tuple[float, ...]:
        return tuple(self.q) if self.q is not None else (10.0,)

    def frequencies(self, dt: float) -> tuple[float, ...]:
        """kind "srs": ascending, per_octave an octave over range_hz (its default for samples dt apart)."""
        from rbhyst.model.periods import octave_frequencies, srs_range

        lo, hi = self.range_hz if self.range_hz is not None else srs_range(dt)
        return tuple(float(f) for f in octave_frequencies(lo, hi, self.per_octave or 12))

    @field_validator("damping", mode="before")
    @classmethod
    def _one_is_a_list(cls, v):
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else v

    @field_validator("damping")
    @classmethod
    def _distinct_dampings(cls, v):
        if len(set(v)) != len(v):
            raise ValueError(f"{v}: each damping once")
        return v

    @field_validator("periods_s")
    @classmethod
    def _distinct_periods(cls, v):
        if v is not None and len(set(v)) != len(v):
            raise ValueError("each period once")
        return v

    @property
    def dampings(self) -> tuple[float, ...]:
        if self.kind == "srs":
            return tuple(1.0 / (2.0 * q) for q in self.qs)
        return tuple(self.damping)

    @property
    def periods(self) -> tuple[float, ...]:
        """Ascending; the default when none are given."""
        if self.periods_s is None:
            return tuple(float(t) for t in default_periods())
        return tuple(sorted(self.periods_s))


class Output(_Model):
    directory: str | None = None
    plots: bool = True
    every: Annotated[int, Field(ge=1)] = 1
    #: points of interest on the body (their motion in time_history.csv, plots, spectra)
    points: list[OutputPoint] | None = None
    #: response spectra (only when present: a run pays for what it asks)
    spectra: Spectra | None = None


class Loops(_Model):
    """Imposed-displacement protocol for ``rbhyst calibrate-plot`` (default: the seed's Fig. 2)."""

    amplitude: float | list[float] = 1.5

    @field_validator("amplitude", mode="before")
    @classmethod
    def _amplitudes(cls, v):
        what = "a positive number (m) or a list of them"
        if _number(v) and v > 0 and np.isfinite(v):
            return float(v)
        if isinstance(v, list) and v and all(_number(x) and x > 0 and np.isfinite(x) for x in v):
            return [float(x) for x in v]
        raise ValueError(f"{v!r} must be {what}")
    frequency_hz: PosFloat = 1.0
    cycles: Annotated[int, Field(ge=1)] = 2
    points_per_cycle: Annotated[int, Field(ge=8)] = 2000


class ShakeTable(_Model):
    """A shake table's limits every made motion keeps within (rbhyst.analyses.qualification.table)."""

    displacement: PosFloat | None = None  # m, peak to peak (the actuator's stroke)
    velocity: PosFloat | None = None  # m/s, peak
    acceleration: PosFloat | None = None  # g, peak


class QualifyShock(_Model):
    """``[qualify] shock``: a shock qualification instead of a seismic one (rbhyst.analyses.shock):
    an SRS specification (``srs``, a CSV) that make-shock matches per axis, or a named pulse."""

    srs: str | None = None  # a CSV: frequency_hz and the maximax SRS with its unit (srs_g, ...)
    q: Annotated[float, Field(gt=0.5)] = 10.0
    method: Literal["wavelets", "damped-sines"] = "wavelets"
    duration: PosFloat | None = None  # s, of each shock made (default: 6 periods of the lowest frequency)
    seed: Annotated[int, Field(ge=0)] = 1
    pulse: str | None = None  # a named pulse (rbhyst.model.shock_pulses.PRESETS)
    compensation: Literal["none", "pre-post"] | None = None
    axes: Annotated[list[Literal["x1", "x2", "x3"]], Field(min_length=1)] | None = None
    shocks: Annotated[int, Field(ge=1, le=10)] = 3
    table: ShakeTable | None = None

    @model_validator(mode="after")
    def _one_shock(self):
        if self.srs is not None and self.pulse is not None:
            raise _key_problems([("pulse", "not with qualify.shock.srs: give an SRS or a pulse")])
        return self


class Qualify(_Model):
    """What ``rbhyst qualify`` holds the deck to (see the documentation, "Qualification"): a required
    response spectrum (a standard's, or files), the motions, and the limits."""

    standard: Literal["ac156", "ieee693"] | None = None
    sds: PosFloat | None = None  # g, with standard = "ac156"
    z_over_h: Annotated[float, Field(ge=0, le=1)] | None = None
    level: Literal["high", "moderate"] | None = None  # with standard = "ieee693": its performance level
    rrs: str | None = None  # a CSV RRS for x1 (horizontal; in space x1 and x2), instead of a standard
    rrs_x2: str | None = None  # ... and for x2 (vertical; in space the second horizontal, when not rrs's)
    rrs_x3: str | None = None  # ... and for x3 (in space: the vertical)
    rrs_damping: Ratio | None = None
    #: how many motions to make, or "deck": the deck's own excitation.support
    motions: Annotated[int, Field(ge=1)] | Literal["deck"] = 1
    seed: Annotated[int, Field(ge=0)] = 1
    duration: PosFloat = 30.0  # s, of each motion made
    motion_dt: PosFloat = 0.005  # s, their sample step
    #: peak total acceleration allowed at a point of interest ("G": the mass centre), g: one
    #: number for every direction or [x1, x2] ([x1, x2, x3] in space: the count is checked
    #: against the deck's by rbhyst qualify)
    acceleration_limit_g: dict[str, PosFloat | Annotated[list[PosFloat], Field(min_length=2, max_length=3)]] | None \
        = None
    #: the force each element can take, N: one number for all, or by CSV name (e1, e2, ...)
    force_capacity_N: PosFloat | dict[str, PosFloat] | None = None
    #: the demand over the motions: "max", the largest (every motion a test that must pass), or
    #: "mean", their mean from seven motions on (ASCE 7-10 16.2.4; fewer: the largest)
    statistic: Literal["max", "mean"] = "max"
    #: the shake table's limits, which every made motion keeps within
    table: ShakeTable | None = None
    #: a shock qualification (an SRS specification or a named pulse) instead of a seismic one
    shock: QualifyShock | None = None

    @model_validator(mode="after")
    def _one_spectrum(self):
        if self.standard is not None and self.rrs is not None:
            raise _key_problems([("rrs", "not with qualify.standard: give a standard or RRS files")])
        if self.shock is not None and (self.standard is not None or self.rrs is not None):
            raise _key_problems([("shock", "not with qualify.standard or qualify.rrs: a deck qualifies to a "
                                           "shock or to a seismic spectrum")])
        return self


class ReportFields(_Model):
    """What report.html prints above its results for the page to be signed (all optional)."""

    project: str | None = None
    equipment: str | None = None
    engineer: str | None = None
    reviewer: str | None = None
    notes: str | None = None


class ShockTest(_Model):
    """What ``rbhyst shock`` holds the deck to (see README, "Shock"): the shock (a named pulse of
    rbhyst.model.shock_pulses.PRESETS, a pulse of its own, or a record), how many along each
    direction of each axis, and the limits (as for ``rbhyst qualify``; strokes from the elements)."""

    pulse: str | Pulse[AccelUnits] | None = None
    record: Record[AccelUnits] | None = None
    #: a named pulse played with pre- and post-pulses ("pre-post") or bare ("none", the default)
    compensation: Literal["none", "pre-post"] | None = None
    #: the axes shocked (default: every axis of the deck), each in both directions
    axes: Annotated[list[Literal["x1", "x2", "x3"]], Field(min_length=1)] | None = None
    #: shocks in each direction of each axis, one after the other in one run (MIL-STD-810H 516.8
    #: Procedure I: three)
    shocks: Annotated[int, Field(ge=1, le=10)] = 3
    acceleration_limit_g: dict[str, PosFloat | Annotated[list[PosFloat], Field(min_length=2, max_length=3)]] | None \
        = None
    force_capacity_N: PosFloat | dict[str, PosFloat] | None = None

    @model_validator(mode="after")
    def _one_shock(self):
        if self.pulse is not None and self.record is not None:
            raise _key_problems([("record", "not with shock.pulse: give a pulse or a record")])
        if self.compensation is not None and not isinstance(self.pulse, str):
            raise _key_problems([("compensation", "only with a named pulse (a pulse of its own says its own "
                                                  "compensation)")])
        return self


class Deck(_Model):
    title: str | None = None
    body: Body | None = None
    hysteresis: Annotated[dict[str, HysteresisSet], Field(min_length=1)]
    elements: Annotated[list[Element], Field(min_length=1)] | None = None
    #: mounts of an axial and shear behaviour, each expanded into uniaxial elements after the
    #: [[elements]] (rbhyst.model.isolators)
    isolators: Annotated[list[Isolator], Field(min_length=1)] | None = None
    #: points resting on the ground, compression only (rbhyst.model.stop), expanded into elements
    #: after the isolators'
    contacts: Annotated[list[Contact], Field(min_length=1)] | None = None
    dampers: list[Damper] | None = None
    damping: Damping | None = None
    excitation: Excitation | None = None
    analysis: Analysis | None = None
    output: Output = Output()
    loops: Loops | None = None
    qualify: Qualify | None = None
    #: who and what the report is for: printed on report.html, never read by the analysis
    report: ReportFields | None = None
    shock: ShockTest | None = None
    #: the file the deck came from (None for one built in code): relative paths resolve beside it
    _source: Path | None = PrivateAttr(default=None)

    @property
    def source(self) -> Path | None:
        return self._source

    @property
    def supports(self) -> bool:
        """Whether the deck has elements: [[elements]], [[isolators]] or both."""
        return self.elements is not None or self.isolators is not None or self.contacts is not None

    @property
    def element_entries(self) -> tuple[tuple[Element, "Origin"], ...]:
        """Every element of the analysis in CSV order (e1, e2, ...; ``count`` not expanded) with
        where it comes from: the [[elements]] entries in deck order, then each isolator's
        (axial, shear 1, shear 2 in space; axial, shear in the plane), isolators in deck order.
        Isolators expand once the body says the deck's dimension (none without a body); built
        at each call (a copy of the deck with other values has its own)."""
        from rbhyst.model.isolators import Origin, expand

        out = [(el, Origin(k)) for k, el in enumerate(self.elements or [], start=1)]
        if self.isolators and self.body is not None:
            n = self.body.dimensions
            for k, iso in enumerate(self.isolators, start=1):
                out += [(el, Origin(k, role)) for el, role in expand(iso, n, Element)]
        if self.contacts and self.body is not None:
            n = self.body.dimensions
            out += [(c.element(n), Origin(k, "contact")) for k, c in enumerate(self.contacts, start=1)]
        return tuple(out)

    @property
    def all_elements(self) -> tuple[Element, ...]:
        """The elements of :attr:`element_entries`, without their origins."""
        return tuple(el for el, _ in self.element_entries)

    @property
    def base(self) -> Path:
        """The folder that relative file paths in the deck resolve against."""
        return self._source.parent if self._source is not None else Path.cwd()

    def with_values(self, values: dict[str, Any]) -> "Deck":
        """A copy with values replaced by dotted keys as in the deck, e.g.
        ``{"hysteresis.wri_shear.loading.kb": 2.2e5, "body.mass": 700.0, "elements[2].count": 3}``.

        Every key but the last must exist in the deck; the result is validated like a deck
        (an InputError names the key and what is wrong).
        """
        data = self.model_dump(mode="python", exclude_unset=True, exclude_defaults=False)
        problems = []
        for key, value in values.items():
            try:
                set_dotted(data, key, value)
            except KeyError as err:
                problems.append(f"{key}: {err.args[0]}")
        if problems:
            raise InputError(problems)
        deck = parse_deck(data)
        deck._source = self._source
        return deck


_KEY_PART = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def split_key(key: str) -> list[str | int]:
    """'elements[2].count' -> ['elements', 1, 'count'] (list indices count from 1, as in error lines)."""
    parts: list[str | int] = []
    pos = 0
    for m in _KEY_PART.finditer(key):
        gap = key[pos:m.start()]
        if gap not in ("", "."):
            raise KeyError("cannot read the key")
        pos = m.end()
        if m.group(2) is not None:
            k = int(m.group(2))
            if k < 1:
                raise KeyError("list indices count from 1")
            parts.append(k - 1)
        elif m.group(1).isdigit() and parts:
            parts.append(int(m.group(1)) - 1)  # elements.2.count: the same as elements[2].count
        else:
            parts.append(m.group(1))
    if not parts or pos != len(key):
        raise KeyError("cannot read the key")
    return parts


#: the unit of each deck key with one, by its path with list indices left out ("*": any name);
#: "" a pure number (a ratio, a count), "signal" the units of the signal it belongs to
KEY_UNITS: dict[tuple[str, ...], str] = {
    ("body", "mass"): "kg", ("body", "inertia"): "kg m²", ("body", "vertices"): "m",
    ("body", "mass_centre"): "m", ("body", "gravity"): "m/s²",
    ("body", "parts", "mass"): "kg", ("body", "parts", "vertices"): "m",
    ("body", "box", "size"): "m", ("body", "box", "centre"): "m",
    ("body", "parts", "box", "size"): "m", ("body", "parts", "box", "centre"): "m",
    **{("hysteresis", "*", "*", name): unit for name, unit in (
        ("kb", "N/m"), ("f0", "N"), ("alpha", "1/m"), ("beta1", "N"), ("beta2", "1/m"), ("gamma1", "N"),
        ("gamma2", "1/m"), ("gamma3", "m"))},
    **{(group, name): unit for group in ("elements", "dampers") for name, unit in (
        ("angle_deg", "°"), ("point", "m"), ("count", ""), ("vertex", ""), ("part", ""), ("direction", ""))},
    ("elements", "stroke"): "m", ("dampers", "c"): "N s/m",
    ("elements", "stop", "gap"): "m", ("elements", "stop", "stiffness"): "N/m", ("elements", "stop", "restitution"): "",
    **{("isolators", "stop", name, key): unit for name in ("axial", "shear", "shear1", "shear2")
       for key, unit in (("gap", "m"), ("stiffness", "N/m"), ("restitution", ""))},
    **{("isolators", name): unit for name, unit in (
        ("axial_deg", "°"), ("shear_deg", "°"), ("point", "m"), ("count", ""), ("vertex", ""), ("part", ""),
        ("axial", ""), ("shear", ""), ("coupling", ""), ("springs", ""), ("reference", "m"))},
    **{("isolators", "stroke", name): "m" for name in ("axial", "shear", "shear1", "shear2")},
    **{("contacts", name): unit for name, unit in (
        ("point", "m"), ("vertex", ""), ("part", ""), ("normal", ""), ("stiffness", "N/m"), ("restitution", ""),
        ("gap", "m"), ("count", ""))},
    **{(*group, "*", name): unit for group in (("excitation", "support"), ("excitation", "force"))
       for name, unit in (("amplitude", "signal"), ("scale", ""), ("frequency_hz", "Hz"), ("phase_deg", "°"),
                          ("start", "s"), ("duration", "s"), ("dt", "s"), ("cycles", ""), ("ramp_cycles", ""),
                          ("rise", "s"), ("compensation_ratio", ""))},
    ("excitation", "force", "point"): "m",
    ("analysis", "dt"): "s", ("analysis", "duration"): "s", ("analysis", "max_omega_dt"): "",
    ("analysis", "max_substep_level"): "", ("analysis", "rtol"): "", ("analysis", "tolerance"): "",
    ("analysis", "warn_error"): "", ("output", "every"): "", ("output", "spectra", "damping"): "",
    ("output", "spectra", "periods_s"): "s", ("output", "spectra", "q"): "",
    ("output", "spectra", "range_hz"): "Hz", ("output", "spectra", "per_octave"): "", ("output", "points", "point"): "m",
    ("loops", "amplitude"): "m", ("loops", "frequency_hz"): "Hz", ("loops", "cycles"): "",
    ("loops", "points_per_cycle"): "",
    ("damping", "rayleigh", "ratio"): "", ("damping", "rayleigh", "frequencies_hz"): "Hz",
    ("damping", "rayleigh", "modes"): "",
    ("qualify", "sds"): "g", ("qualify", "z_over_h"): "", ("qualify", "rrs_damping"): "",
    ("qualify", "motions"): "", ("qualify", "seed"): "", ("qualify", "duration"): "s", ("qualify", "motion_dt"): "s",
    ("qualify", "acceleration_limit_g", "*"): "g", ("qualify", "force_capacity_N"): "N",
    ("qualify", "force_capacity_N", "*"): "N",
    ("shock", "shocks"): "", ("shock", "acceleration_limit_g", "*"): "g", ("shock", "force_capacity_N"): "N",
    ("shock", "force_capacity_N", "*"): "N",
    **{("shock", "pulse", name): unit for name, unit in (("amplitude", "signal"), ("duration", "s"), ("start", "s"),
                                                          ("rise", "s"), ("compensation_ratio", ""))},
    ("shock", "record", "scale"): "", ("shock", "record", "dt"): "s",
    ("qualify", "shock", "q"): "", ("qualify", "shock", "seed"): "", ("qualify", "shock", "shocks"): "",
    ("qualify", "shock", "duration"): "s", ("qualify", "shock", "table", "displacement"): "m",
    ("qualify", "shock", "table", "velocity"): "m/s", ("qualify", "shock", "table", "acceleration"): "g",
}
#: units as written in a deck, as an axis shows them
_SHOWN_UNITS = {"m/s2": "m/s²", "cm/s2": "cm/s²"}


def key_unit(key: str, data: dict | None = None) -> str | None:
    """The unit of a dotted deck key (``"body.mass"`` -> ``"kg"``, ``"elements[2].count"`` ->
    ``""``), None where it has none to tell (a name, a key rbhyst does not know). A signal's
    ``amplitude`` takes the ``units`` beside it in ``data`` (the deck as a mapping)."""
    try:
        parts = split_key(key)
    except KeyError:
        return None
    names = tuple(p for p in parts if isinstance(p, str))
    for pattern, unit in KEY_UNITS.items():
        if len(pattern) == len(names) and all(a in ("*", b) for a, b in zip(pattern, names)):
            break
    else:
        return None
    if unit != "signal":
        return unit
    node: Any = data
    for part in parts[:-1]:
        try:
            node = node[part]
        except (KeyError, IndexError, TypeError):
            return None
    units = node.get("units") if isinstance(node, dict) else None
    return _SHOWN_UNITS.get(units, units) if isinstance(units, str) else None


def set_dotted(data: dict, key: str, value: Any) -> None:
    """Set ``data`` at a dotted deck key; every part but the last must exist (KeyError otherwise)."""
    parts = split_key(key)
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        where = _format_loc(tuple(parts[:i + 1]))
        if isinstance(part, int):
            if not isinstance(node, list) or not 0 <= part < len(node):
                raise KeyError(f"no {where} in the deck")
        elif not isinstance(node, dict) or part not in node or node[part] is None:
            raise KeyError(f"no {where} in the deck")
        node = node[part]
    last = parts[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or not 0 <= last < len(node):
            raise KeyError(f"no {_format_loc(tuple(parts))} in the deck")
    elif not isinstance(node, dict):
        raise KeyError(f"{_format_loc(tuple(parts[:-1]))} is not a table")
    node[last] = value


def cross_references(deck: Deck) -> list[str]:
    """Problems that span sections: undefined sets, vertex indices out of range."""
    problems = []
    for k, el in enumerate(deck.elements or [], start=1):
        if el.hysteresis not in deck.hysteresis:
            problems.append(
                f"elements[{k}].hysteresis: undefined set {el.hysteresis!r}; "
                f"defined: {', '.join(sorted(deck.hysteresis))}"
            )
        if el.vertex is not None and deck.body is not None:
            problems += [f"elements[{k}].{p}" for p in vertex_reference_problems(deck.body, el.part, el.vertex)]
    for k, iso in enumerate(deck.isolators or [], start=1):
        for role in ("axial", "shear", "shear1", "shear2"):
            name = getattr(iso.hysteresis, role)
            if name is not None and name not in deck.hysteresis:
                problems.append(f"isolators[{k}].hysteresis.{role}: undefined set {name!r}; "
                                f"defined: {', '.join(sorted(deck.hysteresis))}")
        if iso.vertex is not None and deck.body is not None:
            problems += [f"isolators[{k}].{p}" for p in vertex_reference_problems(deck.body, iso.part, iso.vertex)]
    for section in ("dampers", "contacts"):
        for k, dp in enumerate(getattr(deck, section) or [], start=1):
            if dp.vertex is not None and deck.body is not None:
                problems += [f"{section}[{k}].{p}" for p in vertex_reference_problems(deck.body, dp.part, dp.vertex)]
    return problems


def _dimension_of(key: str, value, n: int) -> list[str]:
    """A point of the wrong number of coordinates for a deck of n (one line naming the key)."""
    if value is None or len(value) == n:
        return []
    space = "in space (3-D)" if n == 3 else "in the plane (2-D)"
    return [f"{key}: List should have {'at most 2' if n == 2 else 'at least 3'} items: the deck is {space}, as its "
            f"body's first vertex (or box) says, and every point in it has {n} coordinates"]


def dimension_problems(deck: Deck) -> list[str]:
    """A deck is plane or in space throughout: the body's first vertex (or a box) decides, and every
    other vertex, point, mass centre, gravity and direction must agree (one line per key); in
    space, elements take ``direction`` and never ``angle_deg``, in the plane the reverse."""
    if deck.body is None:
        return []
    body = deck.body
    n = body.dimensions
    problems: list[str] = []
    if body.parts is not None:
        for i, p in enumerate(body.parts, start=1):
            if p.box is not None and n == 2:
                problems.append(f"body.parts[{i}].box: a box is a body in space, and body.parts[1] is a polygon "
                                "in the plane (2-D)")
            for j, v in enumerate(p.vertices or [], start=1):
                problems += _dimension_of(f"body.parts[{i}].vertices[{j}]", v, n)
    else:
        for j, v in enumerate(body.vertices or [], start=1):
            problems += _dimension_of(f"body.vertices[{j}]", v, n)
    problems += _dimension_of("body.mass_centre", body.mass_centre, n)
    problems += _dimension_of("body.gravity", body.gravity, n)
    if body.inertia is not None:
        tensor = isinstance(body.inertia, list)
        if tensor and n == 2:
            problems.append("body.inertia: a 3 x 3 tensor is for a body in space; in the plane J_x3 about the mass "
                            "centre is one number (kg m2)")
        elif not tensor and n == 3:
            problems.append("body.inertia: in space the inertia is the 3 x 3 tensor about the mass centre (kg m2), "
                            "[[J11, J12, J13], [J12, J22, J23], [J13, J23, J33]]")
    for section in ("elements", "dampers"):
        for k, el in enumerate(getattr(deck, section) or [], start=1):
            problems += _dimension_of(f"{section}[{k}].point", el.point, n)
            if n == 3:
                if el.angle_deg is not None:
                    problems.append(f"{section}[{k}].angle_deg: the deck is in space (3-D): give the line of action "
                                    "as direction = [d1, d2, d3]")
                elif el.direction is None:
                    problems.append(f"{section}[{k}].direction: required key is missing")
                elif not any(el.direction):
                    problems.append(f"{section}[{k}].direction: [0, 0, 0] has no direction: give the line of "
                                    "action, any length but zero")
            else:
                if el.direction is not None:
                    problems.append(f"{section}[{k}].direction: the deck is in the plane (2-D): give the line of "
                                    "action as angle_deg from x1")
                elif el.angle_deg is None:
                    problems.append(f"{section}[{k}].angle_deg: required key is missing")
    for k, c in enumerate(deck.contacts or [], start=1):
        problems += _dimension_of(f"contacts[{k}].point", c.point, n)
        problems += _dimension_of(f"contacts[{k}].normal", c.normal, n)
    from rbhyst.model.isolators import isolator_problems

    for k, iso in enumerate(deck.isolators or [], start=1):
        problems += isolator_problems(iso, n, f"isolators[{k}]")
    ex = deck.excitation
    if ex is not None and n == 2:
        if ex.support is not None and ex.support.x3 is not None:
            problems.append("excitation.support.x3: the deck is in the plane (2-D): support motion along x1 and x2 "
                            "only")
        if ex.force is not None:
            problems += [f"excitation.force.{k}: the deck is in the plane (2-D): p1, p2 and m3 only"
                         for k in ("p3", "m1", "m2") if getattr(ex.force, k) is not None]
    if ex is not None and ex.force is not None:
        problems += _dimension_of("excitation.force.point", ex.force.point, n)
    for k, p in enumerate(deck.output.points or [], start=1):
        problems += _dimension_of(f"output.points[{k}].point", p.point, n)
        if n == 3 and p.name.lower() in RESERVED_IN_SPACE:
            problems.append(f"output.points[{k}].name: {p.name!r} is taken by rbhyst's own outputs "
                            f"({', '.join(RESERVED_POINT_NAMES[:4] + RESERVED_IN_SPACE + RESERVED_POINT_NAMES[4:])}: "
                            "the mass centre's plots, the ground's spectra): choose another")
    rayleigh = deck.damping.rayleigh if deck.damping is not None else None
    if n == 2 and rayleigh is not None and rayleigh.modes is not None:
        problems += [f"damping.rayleigh.modes[{i}]: must be less than or equal to 3"
                     for i, m in enumerate(rayleigh.modes, start=1) if m > 3]
    return problems


def output_problems(deck: Deck) -> list[str]:
    """Point names used twice (ignoring case: they name files)."""
    problems, seen = [], {}
    for k, p in enumerate(deck.output.points or [], start=1):
        first = seen.setdefault(p.name.lower(), k)
        if first != k:
            problems.append(f"output.points[{k}].name: {p.name!r} is already the name of output.points[{first}]"
                            + (" (names differ only in case, and they name files)" if
                               deck.output.points[first - 1].name != p.name else ""))
    return problems


def vertex_reference_problems(body: Body, part: int | None, vertex: int) -> list[str]:
    """What is wrong with ``part``/``vertex`` of an element on ``body`` ("key: message").

    With parts, ``vertex`` alone is the vertex of part 1 when there is one part and an
    error when there are several (which part's would be a guess); without parts, ``part``
    is an error and ``vertex`` counts body.vertices.
    """
    if body.parts is None:
        if part is not None:
            return ["part: the body has no parts: `vertex` alone counts body.vertices"]
        if vertex > _vertex_count(body):
            return [f"vertex: {vertex} is out of range: the body has {_vertex_count(body)} vertices"]
        return []
    n = len(body.parts)
    if part is None:
        if n > 1:
            return [f"vertex: the body has {n} parts: say whose vertex with `part` (1 to {n})"]
        part = 1
    if part > n:
        return [f"part: {part} is out of range: the body has {n} part{'s' if n > 1 else ''}"]
    nv = _vertex_count(body.parts[part - 1])
    if vertex > nv:
        return [f"vertex: {vertex} is out of range: body.parts[{part}] has {nv} vertices"]
    return []


def _vertex_count(shape) -> int:
    """How many vertices a body or part has: those given, or a box's eight corners."""
    return 8 if shape.vertices is None else len(shape.vertices)


def check_runnable(deck: Deck) -> None:
    """``rbhyst run`` needs a body, elements (or isolators) and an analysis section; loops do not."""
    missing = [f"{key}: required for an analysis" for key in ("body", "analysis") if getattr(deck, key) is None]
    if not deck.supports:
        missing.insert(1 if deck.body is None else 0, f"elements: {SUPPORTS_MISSING}")
    if missing:
        raise InputError(missing)
    a = deck.analysis
    if a.duration is not None and a.dt > a.duration:
        raise InputError(f"analysis.dt: {a.dt} s is larger than analysis.duration = {a.duration} s")
    if deck.excitation is None or (deck.excitation.support is None and deck.excitation.force is None):
        if a.duration is None:
            raise InputError("analysis.duration: required when there is no excitation to take it from")


# ---------------------------------------------------------------- loading


@functools.cache
def _yaml_loader():
    """Safe loading (no object tags) with YAML 1.2 floats, so ``1e-3`` is a number as in TOML.
    Built on the first YAML deck: a TOML deck never imports yaml."""
    import yaml

    class _YamlLoader(yaml.SafeLoader):
        pass

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
    return _YamlLoader


def _format_loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part + 1}]"
        elif part in ("record", "sine", "pulse", "random") or str(part).startswith(("Record[", "Sine[", "Pulse[")):
            continue  # the union's tag is noise to a user
        elif str(part) in PYDANTIC_TYPES or "[" in str(part):
            continue  # (a union member's type name: constrained-float, list[float], function-after[...])
        elif re.fullmatch(r"[A-Za-z0-9_\-]+", str(part)):
            out += ("." if out else "") + str(part)
        else:  # a key with spaces or control characters: quoted, so the message stays one line
            out += f"[{str(part)!r}]"
    return out or "(deck)"


#: the names pydantic gives the members of a union in an error's location: none is a deck key
PYDANTIC_TYPES = frozenset({"constrained-float", "constrained-int", "constrained-str", "float", "int", "str", "bool",
                            "list", "dict", "none", "tagged-union", "union", "literal", "is-instance", "any"})


def _messages(err: ValidationError) -> list[str]:
    lines = []
    errors = err.errors()
    # a value that fails every member of a union (a ratio or a list of them) is said once, by the
    # member whose rule it broke, not by those whose type it does not have ("must be a valid list")
    by_place: dict[str, list[str]] = {}
    for e in errors:
        by_place.setdefault(_format_loc(e["loc"]), []).append(e["type"])
    errors = [e for e in errors if not (e["type"].endswith("_type")
                                        and any(not t.endswith("_type") for t in by_place[_format_loc(e["loc"])]))]
    for e in errors:
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        # pydantic's wording as the deck's other messages word it
        msg = re.sub(r"^Input should be ", "must be ", msg)
        msg = msg.replace("a valid number, unable to parse string as a number", "a number")
        if e["type"] == "extra_forbidden" and e["loc"][-1] == "file" and any(
                t in e["loc"] for t in ("sine", "pulse", "random")):
            lines.append(f"{_format_loc(e['loc'][:-1])}: both a record (`file`) and a signal (`type`): give one; "
                         "a record takes no `type`")
            continue
        if e["type"] == "extra_forbidden":
            msg = "unknown key"
        elif e["type"] == "missing":
            msg = "required key is missing"
        elif e["type"] == "deck_keys":  # several problems, each under its own key
            lines += [f"{_format_loc((*e['loc'], key))}: {m}" for key, m in e["ctx"]["problems"]]
            continue
        elif e["type"] == "union_tag_invalid":
            support = "support" in e["loc"]
            random = ", \"random\"" if support else ""
            msg = (f"unknown type {e['ctx']['tag']!r}: use type = \"sine\"{random} or a pulse "
                   f"({', '.join(repr(p) for p in PULSES)}), or give `file` (and no type) for a record")
            if e["ctx"]["tag"] == "random" and not support:
                msg = "type \"random\" is random vibration of the support: excitation.support.x1 or x2 only"
        lines.append(f"{_format_loc(e['loc'])}: {msg}")
    return list(dict.fromkeys(lines))


#: the sections an analysis needs (a deck for calibrate-plot needs only [hysteresis]);
#: [[isolators]] stand for [[elements]]
ANALYSIS_SECTIONS = ("body", "elements", "analysis")
SUPPORTS_MISSING = "required for an analysis ([[elements]] or [[isolators]])"


def _missing(data: dict, need: tuple[str, ...]) -> list[str]:
    """The sections of ``need`` that ``data`` lacks (one line each); [[isolators]] give elements."""
    out = []
    for key in need:
        if key == "elements" and data.get(key) is None:
            if data.get("isolators") is None:
                out.append(f"elements: {SUPPORTS_MISSING}")
        elif data.get(key) is None:
            out.append(f"{key}: required for an analysis")
    return out


def parse_deck(data: Any, need: tuple[str, ...] = ()) -> Deck:
    """Validate a parsed mapping; raise InputError with one line per problem, every problem at
    once: those of the keys given and every section of ``need`` that is missing."""
    if not isinstance(data, dict):
        raise InputError("(deck): the top level must be a table of keys")
    missing = _missing(data, need)
    try:
        deck = Deck.model_validate(data)
    except ValidationError as err:
        raise InputError(_messages(err) + missing) from None
    problems = missing + dimension_problems(deck) + cross_references(deck) + output_problems(deck)
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
        import yaml

        try:
            data = yaml.load(text, Loader=_yaml_loader())
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark
            where = f" (at line {mark.line + 1}, column {mark.column + 1})" if mark else ""
            raise InputError(f"{path}: YAML error: {exc.problem}{where}") from None
        except yaml.YAMLError as exc:
            raise InputError(f"{path}: YAML error: {exc}") from None
        return data if data is not None else {}
    raise InputError(f"{path}: unknown deck format {suffix!r}; use .toml, .yaml or .yml")


def load_deck(path: str | Path, need: tuple[str, ...] = ()) -> Deck:
    """Read and validate a deck file; relative paths in it resolve beside it. ``need``: sections
    it must have (ANALYSIS_SECTIONS for a run), named with every other problem at once."""
    deck = parse_deck(read_mapping(Path(path)), need)
    deck._source = Path(path).resolve()
    return deck

