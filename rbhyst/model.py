"""Assemble a validated deck into a :class:`System` of plain arrays (seed eqs. 1-13).

Pydantic objects stop here: everything downstream sees numpy arrays, floats and
callables of time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from . import deck as dk
from .errors import InputError
from .geometry import Polygon, PolygonError, polygon
from .hysteresis import limiting_slope, reversal_stiffness
from .records import Series, read_series

Signal = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Excitation:
    """Support acceleration (m/s2) and external generalized forces at G (N, N m)."""

    ag1: Signal | None = None
    ag2: Signal | None = None
    p1: Signal | None = None
    p2: Signal | None = None
    m3: Signal | None = None
    point: tuple[float, float] = (0.0, 0.0)  # where p1, p2 act, relative to G
    duration: float | None = None  # of the longest record or finite pulse
    finest_dt: float | None = None  # the finest record step

    @property
    def has_support(self) -> bool:
        return self.ag1 is not None or self.ag2 is not None

    def support(self, t: np.ndarray) -> np.ndarray:
        """(n, 2) support acceleration."""
        out = np.zeros((len(t), 2))
        if self.ag1 is not None:
            out[:, 0] = self.ag1(t)
        if self.ag2 is not None:
            out[:, 1] = self.ag2(t)
        return out

    def load(self, t: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """(n, 3) generalized load p = -M (ag1, ag2, 0) + (p1, p2, p3), eq. 13 for p3."""
        p = np.zeros((len(t), 3))
        if self.has_support:
            ag = self.support(t)
            p[:, 0] -= mass[0] * ag[:, 0]
            p[:, 1] -= mass[1] * ag[:, 1]
        x1p, x2p = self.point
        if self.p1 is not None:
            f = self.p1(t)
            p[:, 0] += f
            p[:, 2] -= f * x2p
        if self.p2 is not None:
            f = self.p2(t)
            p[:, 1] += f
            p[:, 2] += f * x1p
        if self.m3 is not None:
            p[:, 2] += self.m3(t)
        return p


@dataclass(frozen=True)
class Element:
    """One [[elements]] entry as the user wrote it; ``row`` is its row in the kernel arrays."""

    x: tuple[float, float]  # attachment point relative to G, m
    angle_deg: float
    hysteresis: str
    count: int
    row: int


@dataclass(frozen=True)
class System:
    """The rigid body on its elements: M q'' + R(q) = p(t), q = (u1, u2, theta3)."""

    title: str
    body: Polygon
    mass: np.ndarray  # (3,) diag(m, m, J)
    # kernel rows: elements with the same b and set deform alike and are evaluated once
    bvec: np.ndarray  # (ne, 3) rows b_e = (cos a, sin a, x1 sin a - x2 cos a)
    mult: np.ndarray  # (ne,) how many identical elements each row stands for
    params: np.ndarray  # (ne, 2, 8) VRM sets
    k0: np.ndarray  # (ne,) elastic stiffness of each element: the K0 of the structure-dependent methods
    k_reversal: np.ndarray  # (ne,) stiffness at a reversal at u = 0 (the stiffest instant of a loop)
    elements: tuple[Element, ...]
    excitation: Excitation
    notes: tuple[str, ...] = field(default=())

    @property
    def K0(self) -> np.ndarray:
        """B diag(mult k0) B^T: the stiffness the structure-dependent methods are built on.

        k0 is the slope of the limiting curves at u = 0 (kb + ke(0), the larger branch), the
        stiffness an element returns to away from reversals. Measured on the seed scene, this
        makes Chang's method 30x more accurate at dt = 1 ms than the reversal stiffness
        k_a = kb + alpha (f0+ + f0-), whose large omega_0 h damps the displacement predictor.
        Stability where the tangent exceeds K0 (at reversals, on stiffening branches) is kept
        by the loop's stiffness monitor: omega_t h <= 0.5 < 2 for every method.
        """
        return (self.bvec.T * (self.mult * self.k0)) @ self.bvec

    @property
    def n_output_elements(self) -> int:
        return int(self.mult.sum())

    def expand(self, per_row: np.ndarray) -> np.ndarray:
        """(n, rows) kernel data to (n, elements) in CSV order: deck order, ``count`` expanded."""
        columns = [el.row for el in self.elements for _ in range(el.count)]
        return per_row[:, columns]

    def row_elements(self, row: int) -> list[int]:
        """CSV numbers (1-based) of the elements that kernel row ``row`` stands for."""
        out, k = [], 1
        for el in self.elements:
            if el.row == row:
                out.extend(range(k, k + el.count))
            k += el.count
        return out


def b_vector(x1: float, x2: float, angle_rad: float) -> np.ndarray:
    """u_e = b . q for an element at (x1, x2) along angle a (eqs. 5-8 combined)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([c, s, x1 * s - x2 * c])


def free_directions(bvec: np.ndarray, body: Polygon) -> list[str]:
    """Describe each rigid motion q != 0 with B^T q = 0: no element resists it."""
    size = float(np.max(np.abs(body.vertices))) or 1.0
    scaled = bvec * np.array([1.0, 1.0, 1.0 / size])  # rotation in m at the body's size
    _, sv, vt = np.linalg.svd(scaled, full_matrices=True)
    sv = np.concatenate([sv, np.zeros(3 - len(sv))])
    out = []
    for k in range(3):
        if sv[k] > 1e-9 * max(sv[0], 1e-300):
            continue
        q = vt[k] * np.array([1.0, 1.0, 1.0 / size])
        u1, u2, th = q
        if abs(th) * size < 1e-9 * max(abs(u1), abs(u2)):
            ang = math.degrees(math.atan2(u2, u1)) % 180.0
            out.append(f"translation along {ang:.4g} deg from x1")
        else:
            c1, c2 = -u2 / th, u1 / th
            if abs(c1) < 1e-9 * size and abs(c2) < 1e-9 * size:
                out.append("rotation about the centroid G")
            else:
                out.append(f"rotation about the point ({c1 + 0.0:.6g}, {c2 + 0.0:.6g}) m from G")
    return out


def _signal(spec, scale_units: dict[str, float], base: Path) -> tuple[Signal, float | None, float | None]:
    """A callable of time in SI units, the signal's own duration and record step."""
    factor = scale_units[spec.units]
    if isinstance(spec, dk.Sine):
        w = 2.0 * math.pi * spec.frequency_hz
        t0 = spec.start
        t1 = math.inf if spec.cycles is None else t0 + spec.cycles / spec.frequency_hz
        amp = spec.amplitude * factor
        ph = math.radians(spec.phase_deg)

        def sine(t, amp=amp, w=w, t0=t0, t1=t1, ph=ph):
            t = np.asarray(t, dtype=float)
            on = (t >= t0) & (t <= t1)
            return np.where(on, amp * np.sin(w * (t - t0) + ph), 0.0)

        return sine, (None if math.isinf(t1) else t1), None
    path = Path(spec.file)
    if not path.is_absolute():
        path = base / path
    series = read_series(path, spec.dt)
    series = Series(series.t0, series.dt, series.values * factor * spec.scale)
    return series, series.duration, series.dt


def _excitation(deck: dk.Deck, base: Path, body: Polygon) -> Excitation:
    ex = deck.excitation
    if ex is None:
        return Excitation()
    sig: dict[str, Signal] = {}
    durations, steps = [], []
    problems = []

    def add(name, spec, units, loc):
        if spec is None:
            return
        try:
            s, dur, step = _signal(spec, units, base)
        except InputError as err:
            problems.extend(f"{loc}: {p}" for p in err.problems)
            return
        sig[name] = s
        if dur is not None:
            durations.append(dur)
        if step is not None:
            steps.append(step)

    if ex.support is not None:
        add("ag1", ex.support.x1, dk.ACCEL_UNITS, "excitation.support.x1")
        add("ag2", ex.support.x2, dk.ACCEL_UNITS, "excitation.support.x2")
    point = (0.0, 0.0)
    if ex.force is not None:
        add("p1", ex.force.p1, dk.FORCE_UNITS, "excitation.force.p1")
        add("p2", ex.force.p2, dk.FORCE_UNITS, "excitation.force.p2")
        add("m3", ex.force.m3, dk.MOMENT_UNITS, "excitation.force.m3")
        # the point is given in the deck's frame; loads act about G
        point = (ex.force.point[0] - body.centroid[0], ex.force.point[1] - body.centroid[1])
    if problems:
        raise InputError(problems)
    return Excitation(
        point=point,
        duration=max(durations) if durations else None,
        finest_dt=min(steps) if steps else None,
        **sig,
    )


def assemble(deck: dk.Deck, base: Path) -> System:
    """Build the System of a runnable deck; relative file paths resolve against ``base``."""
    dk.check_runnable(deck)
    try:
        body = polygon(deck.body.vertices)
    except PolygonError as err:
        raise InputError(f"body.vertices: {err}") from None
    notes = []
    if body.reordered:
        notes.append("body.vertices are clockwise: taken in reverse order for eqs. 2-4")
    size = float(np.max(np.abs(body.vertices)))
    if np.hypot(*body.centroid) > 1e-9 * size:
        notes.append(
            "body.vertices are not centred on the centroid: coordinates shifted by "
            f"({-body.centroid[0]:.6g}, {-body.centroid[1]:.6g}) m so that G is the origin"
        )
    m = deck.body.mass
    mass = np.array([m, m, body.polar_inertia(m)])

    sets = {name: hs.array() for name, hs in deck.hysteresis.items()}
    k_rev, k_el = {}, {}
    for name, p in sets.items():
        k = reversal_stiffness(p, 0.0)
        if not k > 0.0:
            raise InputError(f"hysteresis.{name}: the stiffness at a reversal at u = 0 is {k:.6g} N/m; it must be > 0")
        k_rev[name] = k
        k_el[name] = max(float(limiting_slope(p, 1, 0.0)), float(limiting_slope(p, -1, 0.0)), 0.0)

    rows, mult, names, elements = [], [], [], []
    for el in deck.elements:
        if el.vertex is not None:
            x = body.vertices[el.vertex - 1]
        else:
            x = np.asarray(el.point, dtype=float) - body.centroid
        b = b_vector(x[0], x[1], math.radians(el.angle_deg))
        # an element that deforms exactly like an earlier one with the same set adds to its
        # row: the seed's shear isolators under P1 and P2 share b = (0, 1, x1)
        same = [r for r, (bb, nn) in enumerate(zip(rows, names))
                if nn == el.hysteresis and np.allclose(bb, b, rtol=0.0, atol=1e-12)]
        if same:
            row = same[0]
            mult[row] += el.count
        else:
            row = len(rows)
            rows.append(b)
            names.append(el.hysteresis)
            mult.append(el.count)
        elements.append(Element((float(x[0]), float(x[1])), el.angle_deg, el.hysteresis, el.count, row))
    bvec = np.array(rows)
    free = free_directions(bvec, body)
    if free:
        raise InputError(f"elements: the body is not restrained against {'; '.join(free)}")

    excitation = _excitation(deck, base, body)
    return System(
        title=deck.title or "",
        body=body,
        mass=mass,
        bvec=bvec,
        mult=np.array(mult, dtype=float),
        params=np.array([sets[n] for n in names]),
        k0=np.array([k_el[n] for n in names]),
        k_reversal=np.array([k_rev[n] for n in names]),
        elements=tuple(elements),
        excitation=excitation,
        notes=tuple(notes),
    )
