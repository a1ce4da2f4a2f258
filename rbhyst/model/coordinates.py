"""The generalized coordinates of a rigid body, and the names and units of the columns they head.

The seed's body has q = (u1, u2, theta3): the translations of its mass centre G along x1 and x2
and the rotation about x3 (seed section 2.2). The solve layer takes the number of coordinates
from the arrays it is given and their names from here, so a body with other coordinates (a
three-dimensional one: three translations and three rotations) is a tuple of
:class:`Coordinate` and the arrays that go with it, not another kernel.
"""

from __future__ import annotations

from dataclasses import dataclass

#: the column families a coordinate heads: displacement, velocity, relative and total
#: acceleration, and the elements' resultant along it (force or moment)
FAMILIES = ("d", "v", "a", "at", "R")


@dataclass(frozen=True)
class Coordinate:
    """A translation of G along the axis x_axis, or a rotation about it; each family's column
    is ``key_unit`` (``u1_m``, ``alphat3_rad_s2``), its key the name without the unit (``u1``)."""

    axis: int  # 1, 2 or 3
    rotation: bool
    d: tuple[str, str]  # (key, unit)
    v: tuple[str, str]
    a: tuple[str, str]
    at: tuple[str, str]
    R: tuple[str, str]

    def key(self, family: str) -> str:
        return getattr(self, family)[0]

    def column(self, family: str) -> str:
        key, unit = getattr(self, family)
        return f"{key}_{unit}"


def translation(axis: int) -> Coordinate:
    """u_k (m) of G along x_k, and its velocity, accelerations and force resultant."""
    k = axis
    return Coordinate(k, False, (f"u{k}", "m"), (f"v{k}", "m_s"), (f"a{k}", "m_s2"), (f"at{k}", "m_s2"),
                      (f"R{k}", "N"))


def rotation(axis: int, resultant: str | None = None) -> Coordinate:
    """theta_k (rad) about x_k, and its rates and moment resultant (``resultant``: the moment's
    key where R_k would repeat a force's)."""
    k = axis
    return Coordinate(k, True, (f"theta{k}", "rad"), (f"omega{k}", "rad_s"), (f"alpha{k}", "rad_s2"),
                      (f"alphat{k}", "rad_s2"), (resultant or f"R{k}", "Nm"))


#: the seed's plane body: q = (u1, u2, theta3)
PLANE = (translation(1), translation(2), rotation(3))
#: a body in space: q = (u1, u2, u3, theta1, theta2, theta3); the moment resultants are R4..R6
#: (N m) so that no key repeats a force's
SPACE = (translation(1), translation(2), translation(3), rotation(1, "R4"), rotation(2, "R5"), rotation(3, "R6"))


def columns(coordinates, family: str) -> list[str]:
    """Every coordinate's column of one family, in the order of q."""
    return [c.column(family) for c in coordinates]


def translations(coordinates) -> list[int]:
    """The indices in q of the translations, in order: the directions a point of the body, a
    support motion and a force have."""
    return [j for j, c in enumerate(coordinates) if not c.rotation]
