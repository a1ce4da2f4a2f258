"""``[[isolators]]``: a mount with an axial and shear behaviour (a wire rope isolator) as one deck
entry with local axes, expanded into uncoupled uniaxial elements (the VRM is uniaxial: the
isolator's directions are not coupled, so its axial-shear interaction is not modelled).

The expansion gives exactly the elements a user would write by hand: after every ``[[elements]]``
entry, each isolator in deck order as its axial element, then shear 1 and shear 2 in space (its one
shear element in the plane), each with the isolator's place, ``count`` and the set and stroke of
its direction. The pydantic model is :class:`rbhyst.model.deck.Isolator`; this module holds its
geometry: the default shear lines, the checks that need the deck's dimension, the expansion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: a shear line may be this far from perpendicular to the axial line (and to the other shear line)
PERPENDICULAR_TOLERANCE_DEG = 0.1

#: the elements of an isolator, in their order in the CSV
ROLES_SPACE = ("axial", "shear1", "shear2")
ROLES_PLANE = ("axial", "shear")


@dataclass(frozen=True)
class Origin:
    """Where an element of the analysis comes from: ``[[elements]]`` entry ``index`` (role None) or
    one direction of ``[[isolators]]`` entry ``index`` (both 1-based, as in error lines)."""

    index: int
    role: str | None = None

    @property
    def isolator(self) -> int | None:
        return self.index if self.role not in (None, "contact") else None

    @property
    def label(self) -> str:
        """'elements[3]', 'isolators[2] shear1' or 'contacts[1]', as a user finds it in the deck."""
        if self.role == "contact":
            return f"contacts[{self.index}]"
        return f"elements[{self.index}]" if self.role is None else f"isolators[{self.index}] {self.role}"


def _unit(v) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    return a / np.linalg.norm(a)


def _clean(v) -> list[float]:
    """Plain floats, without negative zeros (they would print as -0 in summary.json)."""
    return [float(x) + 0.0 for x in v]


def default_shear(axial) -> tuple[list[float], list[float]]:
    """The two shear lines of an isolator in space that gives none: perpendicular to the axial line
    and to each other, each as near a deck axis as can be. Of the deck's axes x1, x2, x3, the one
    nearest the axial line (the largest |component|, the first on ties) is left out; the other
    two, in their order, are made perpendicular to the axial line (and the second to the first)
    by Gram-Schmidt. An axial line along x3 gives x1 and x2, along x1 gives x2 and x3, along x2
    gives x1 and x3, each pointing to the positive side of its deck axis."""
    a = _unit(axial)
    j = int(np.argmax(np.abs(a)))
    p, q = (i for i in range(3) if i != j)
    e = np.eye(3)
    s1 = e[p] - a[p] * a
    s1 = s1 / np.linalg.norm(s1)
    s2 = e[q] - a[q] * a - s1[q] * s1
    s2 = s2 / np.linalg.norm(s2)
    return _clean(s1), _clean(s2)


def default_shear_deg(axial_deg: float) -> float:
    """The shear line of an isolator in the plane that gives none: axial_deg +- 90 deg, the one
    pointing to the positive side of the deck axis farther from the axial line (x1 for an axial
    line within 45 deg of x2, else x2), as an angle from 0 to 360 deg: axial 270 or -90 (down)
    and 90 give 0, axial 0 and 180 give 90, as the rule in space does. (0, not 360: the sine of
    2 pi is not the sine of 0 in floating point, and a hand-written 0 must run the same.)"""
    r = axial_deg % 180.0
    near_x1 = min(r, 180.0 - r) <= 45.0
    a = math.radians(axial_deg)
    if near_x1:  # the shear line's x2 component, sin(a + 90) = cos(a), must be positive
        shear = axial_deg + 90.0 if math.cos(a) > 0.0 else axial_deg - 90.0
    else:  # its x1 component, cos(a + 90) = -sin(a), must be positive
        shear = axial_deg + 90.0 if math.sin(a) < 0.0 else axial_deg - 90.0
    return shear % 360.0 + 0.0


def _fmt(v) -> str:
    return "[" + ", ".join(f"{x:g}" for x in v) + "]"


def _off_perpendicular(a, b) -> float:
    """How far (deg) the lines a and b are from perpendicular."""
    c = abs(float(np.dot(_unit(a), _unit(b))))
    return 90.0 - math.degrees(math.acos(min(c, 1.0)))


def isolator_problems(iso, n: int, key: str) -> list[str]:
    """What is wrong with isolator ``iso`` (rbhyst.model.deck.Isolator) in a deck of ``n``
    dimensions, one line per key ("isolators[2].shear[1]: ..."): keys of the other dimension,
    missing ones, zero vectors, shear lines not perpendicular."""
    problems: list[str] = []
    tol = PERPENDICULAR_TOLERANCE_DEG
    if iso.point is not None and len(iso.point) != n:
        space = "in space (3-D)" if n == 3 else "in the plane (2-D)"
        problems.append(f"{key}.point: List should have {'at most 2' if n == 2 else 'at least 3'} items: the deck "
                        f"is {space}, as its body's first vertex (or box) says, and every point in it has {n} "
                        "coordinates")
    sets, strokes = iso.hysteresis, iso.stroke
    if n == 3:
        problems += [f"{key}.{k}: the deck is in space (3-D): give the {what} as {instead}"
                     for k, what, instead in (("axial_deg", "axial line", "axial = [d1, d2, d3]"),
                                              ("shear_deg", "shear lines", "shear = [[d1, d2, d3], [d1, d2, d3]]"))
                     if getattr(iso, k) is not None]
        if iso.axial is None:
            if iso.axial_deg is None:
                problems.append(f"{key}.axial: required key is missing")
        elif len(iso.axial) != 3:
            problems.append(f"{key}.axial: {_fmt(iso.axial)}: the deck is in space (3-D): three components "
                            "[d1, d2, d3]")
        elif not any(iso.axial):
            problems.append(f"{key}.axial: {_fmt(iso.axial)} has no direction: give the axial line, any length "
                            "but zero")
        axial_ok = iso.axial is not None and len(iso.axial) == 3 and any(iso.axial)
        if iso.shear is not None and len(iso.shear) != 2:
            problems.append(f"{key}.shear: {len(iso.shear)} line{'s' if len(iso.shear) > 1 else ''} given: an "
                            "isolator in space has two shear lines, [[d1, d2, d3], [d1, d2, d3]] (or leave it out "
                            "for the default ones)")
        elif iso.shear is not None:
            good = []
            for i, s in enumerate(iso.shear, start=1):
                if len(s) != 3:
                    problems.append(f"{key}.shear[{i}]: {_fmt(s)}: the deck is in space (3-D): three components "
                                    "[d1, d2, d3]")
                elif not any(s):
                    problems.append(f"{key}.shear[{i}]: {_fmt(s)} has no direction: give the shear line, any "
                                    "length but zero")
                elif axial_ok and _off_perpendicular(s, iso.axial) > tol:
                    problems.append(f"{key}.shear[{i}]: {_fmt(s)} is {_angle(s, iso.axial):.4g} deg from the "
                                    f"axial line {_fmt(iso.axial)}: a shear line is perpendicular to it (within "
                                    f"{tol:g} deg)")
                else:
                    good.append(i)
            if good == [1, 2] and _off_perpendicular(iso.shear[0], iso.shear[1]) > tol:
                problems.append(f"{key}.shear[2]: {_fmt(iso.shear[1])} is {_angle(iso.shear[0], iso.shear[1]):.4g} "
                                f"deg from shear[1] {_fmt(iso.shear[0])}: the two shear lines are perpendicular "
                                f"to each other (within {tol:g} deg)")
        if sets.shear is None:
            problems += [f"{key}.hysteresis.{k}: required key is missing (or one `shear` set for both shear lines)"
                         for k in ("shear1", "shear2") if getattr(sets, k) is None]
        problems += _coupling_problems(iso, key)
    else:
        problems += _plane_problems(iso, key)
    return problems


def _plane_problems(iso, key: str) -> list[str]:
    """isolator_problems of an isolator in the plane."""
    problems: list[str] = []
    tol = PERPENDICULAR_TOLERANCE_DEG
    sets, strokes = iso.hysteresis, iso.stroke
    if iso.axial is not None:
        problems.append(f"{key}.axial: the deck is in the plane (2-D): give the axial line as axial_deg from x1 "
                        "(counterclockwise)")
    elif iso.axial_deg is None:
        problems.append(f"{key}.axial_deg: required key is missing")
    if iso.shear is not None:
        problems.append(f"{key}.shear: the deck is in the plane (2-D): give the shear line as shear_deg from "
                        "x1, or leave it out (axial_deg +- 90)")
    if iso.axial_deg is not None and iso.shear_deg is not None:
        off = abs((iso.shear_deg - iso.axial_deg) % 180.0 - 90.0)
        if off > tol:
            problems.append(f"{key}.shear_deg: {iso.shear_deg:g} is {90.0 - off:.4g} deg from axial_deg = "
                            f"{iso.axial_deg:g}: the shear line is perpendicular to the axial line (within "
                            f"{tol:g} deg)")
    for group, name in ((sets, "hysteresis"), (strokes, "stroke")):
        if group is None:
            continue
        problems += [f"{key}.{name}.{k}: the deck is in the plane (2-D): an isolator has one shear line there "
                     f"(`shear`)" for k in ("shear1", "shear2") if getattr(group, k) is not None]
    if sets.shear is None and sets.shear1 is None and sets.shear2 is None:
        problems.append(f"{key}.hysteresis.shear: required key is missing")
    if iso.coupling == "mss":
        problems.append(f"{key}.coupling: \"mss\" couples two shear lines: an isolator in the plane (2-D) has "
                        "one; leave it out (\"none\")")
    problems += [f"{key}.{k}: goes with coupling = \"mss\" (in space)" for k in ("springs", "reference")
                 if getattr(iso, k) is not None]
    return problems


def _coupling_problems(iso, key: str) -> list[str]:
    """What is wrong with an isolator's coupling keys in space, one line per key."""
    if iso.coupling != "mss":
        return [f"{key}.{k}: goes with coupling = \"mss\"" for k in ("springs", "reference")
                if getattr(iso, k) is not None]
    problems = []
    if iso.springs is not None and iso.springs % 2:
        problems.append(f"{key}.springs: {iso.springs}: an even number (a spring along each shear line), 4 or more")
    sets = iso.hysteresis
    if sets.shear is None and sets.shear1 != sets.shear2:
        problems.append(f"{key}.hysteresis.shear2: {sets.shear2!r} is not shear1's {sets.shear1!r}: a multiple "
                        "shear spring has one behaviour in its plane; give one `shear` set")
    for group, what in ((iso.stroke, "stroke"), (iso.stop, "stop")):
        if group is not None:
            problems += [f"{key}.{what}.{k}: not with coupling = \"mss\" (its shear is one deformation in the "
                         "plane, not two)" for k in ("shear", "shear1", "shear2") if getattr(group, k) is not None]
    return problems


def _angle(a, b) -> float:
    """The angle (deg, 0 to 90) between the lines a and b."""
    c = abs(float(np.dot(_unit(a), _unit(b))))
    return math.degrees(math.acos(min(c, 1.0)))


def expand(iso, n: int, element_cls) -> list[tuple[object, str]]:
    """The uniaxial elements of a checked isolator (``element_cls``: rbhyst.model.deck.Element),
    with their roles: axial, shear1, shear2 in space; axial, shear in the plane."""
    place = {k: getattr(iso, k) for k in ("part", "vertex", "point") if getattr(iso, k) is not None}
    sets, strokes, stops = iso.hysteresis, iso.stroke, iso.stop

    def pick(group, role):
        if group is None:
            return None
        if role in ("shear1", "shear2") and group.shear is not None:
            return group.shear
        return getattr(group, role)

    out = []
    if n == 3:
        shear = iso.shear if iso.shear is not None else default_shear(iso.axial)
        lines = (list(iso.axial), list(shear[0]), list(shear[1]))
        if iso.coupling == "mss":
            return _expand_mss(iso, place, lines, element_cls, pick(strokes, "axial"), pick(stops, "axial"))
        for role, line in zip(ROLES_SPACE, lines):
            out.append((element_cls(**place, direction=line, hysteresis=pick(sets, role), count=iso.count,
                                    **_limits(pick(strokes, role), pick(stops, role))), role))
    else:
        shear_deg = iso.shear_deg if iso.shear_deg is not None else default_shear_deg(iso.axial_deg)
        for role, angle in zip(ROLES_PLANE, (iso.axial_deg, shear_deg)):
            out.append((element_cls(**place, angle_deg=angle, hysteresis=pick(sets, role), count=iso.count,
                                    **_limits(pick(strokes, role), pick(stops, role))), role))
    return out


def _limits(stroke, stop) -> dict:
    """An element's ``stroke`` and ``stop`` keys, those given."""
    return {**({"stroke": stroke} if stroke is not None else {}), **({"stop": stop} if stop is not None else {})}


def mss_set_name(name: str, springs: int, reference: float | None) -> str:
    """The name of the springs' set of an MSS of set ``name`` (rbhyst.model.mss.spring_set): what
    the kernels' rows and the summary's elements call it."""
    return f"{name} (mss {springs}" + (f", {reference:g} m)" if reference is not None else ")")


def _expand_mss(iso, place, lines, element_cls, axial_stroke, axial_stop) -> list[tuple[object, str]]:
    """An MSS isolator's elements: the axial one, then its springs at pi i / n from shear line 1
    towards shear line 2 (roles mss1 .. mssn), each of the springs' set."""
    from rbhyst.model.mss import DEFAULT_SPRINGS, spring_cosines, spring_label

    n = iso.springs or DEFAULT_SPRINGS
    sets = iso.hysteresis
    name = mss_set_name(sets.shear or sets.shear1, n, iso.reference)
    out = [(element_cls(**place, direction=lines[0], hysteresis=sets.axial, count=iso.count,
                        **_limits(axial_stroke, axial_stop)), "axial")]
    s1, s2 = _unit(lines[1]), _unit(lines[2])
    for i, (c, s) in enumerate(zip(*spring_cosines(n)), start=1):
        out.append((element_cls(**place, direction=_clean(c * s1 + s * s2), hysteresis=name, count=iso.count),
                    spring_label(i)))
    return out
