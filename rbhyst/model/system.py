"""Assemble a validated deck into a :class:`System` of plain arrays (seed eqs. 1-13).

Pydantic objects stop here: everything downstream sees numpy arrays, floats and
callables of time.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from rbhyst.model import deck as dk
from rbhyst.model import signals
from rbhyst.errors import InputError
from rbhyst.model.body import Body, body_from_deck
from rbhyst.model.coordinates import PLANE, Coordinate, translations
from rbhyst.model.hysteresis import limiting_slope, reversal_stiffness, virgin_tangent
from rbhyst.files.units import check_declared
from rbhyst.model.points import point_matrix
from rbhyst.model.records import ScaledSeries, Series, read_record

Signal = Callable[[np.ndarray], np.ndarray]


class RecordEdges:
    """A record as signals.hat_average sees it near where it jumps (its start after t = 0 and its
    end, where its first and last samples are not zero: it is zero outside them): the samples
    near them are its breakpoints, so that the hat's halves are integrated piece by piece."""

    def __init__(self, series, jumps: tuple[float, ...], h: float):
        self.series = series
        times, reach = series.times, 2.0 * h + series.dt
        self.breakpoints = tuple(float(x) for b in jumps
                                 for x in times[np.searchsorted(times, b - reach):np.searchsorted(times, b + reach,
                                                                                                  side="right")])

    def __call__(self, t):
        return self.series(t)


def record_jumps(series) -> tuple[float, ...]:
    """The times a record jumps: its start (after t = 0) and its end, where its first or last
    sample is not zero (one that starts and ends at zero is linear between its samples
    everywhere, which the nodes that hold them follow exactly)."""
    values = series.values
    if len(values) == 0:
        return ()
    out = []
    if series.start > 0.0 and values[0] != 0.0:
        out.append(float(series.start))
    if values[-1] != 0.0:
        out.append(float(series.end))
    return tuple(out)


#: a record whose step and start are not a whole number of dt / n for any n up to this is followed
#: at ceil(dt / step) substeps (its samples then between the nodes, as before)
MAX_ALIGNMENT = 1000


def record_alignment(dt: float, step: float, start: float = 0.0) -> int:
    """The fewest compute steps per step of dt whose nodes hold every sample of a record of
    ``step`` starting at ``start``: q with step / dt = p / q and start / dt = a / b in lowest
    terms, their least common multiple (1 where dt's own nodes do; the seed's 10 ms record at
    1 ms). A ratio with no such q up to MAX_ALIGNMENT: 1 (the samples fall between nodes)."""
    from fractions import Fraction

    out = 1
    for ratio in (step / dt, start / dt):
        if ratio == 0.0:
            continue
        f = Fraction(ratio).limit_denominator(MAX_ALIGNMENT)
        if abs(float(f) - ratio) > 1e-9 * max(1.0, abs(ratio)):
            return 1
        out = math.lcm(out, f.denominator)
    return out if out <= MAX_ALIGNMENT else 1


@dataclass(frozen=True)
class Excitation:
    """Support acceleration (m/s2) and external generalized forces at G (N, N m)."""

    ag1: Signal | None = None
    ag2: Signal | None = None
    p1: Signal | None = None
    p2: Signal | None = None
    m3: Signal | None = None
    point: tuple[float, ...] = (0.0, 0.0)  # where p1, p2 (p3) act, relative to G
    #: a load that does not vary (n,): the weight, once the static equilibrium under it is known;
    #: None: zero
    constant: tuple[float, ...] | None = None
    duration: float | None = None  # of the longest record or finite pulse
    #: how a unit of each signal enters the n generalized loads (:func:`load_directions`): a
    #: support acceleration along its influence vector r (as -M r), a force or moment along its
    #: generalized force (eq. 13); None: those of the seed's plane body with the forces at ``point``
    directions: dict[str, tuple[float, ...]] | None = None
    # a body in space: support motion along x3, a force along x3, moments about x1 and x2
    ag3: Signal | None = None
    p3: Signal | None = None
    m1: Signal | None = None
    m2: Signal | None = None
    #: exact kinematics with p1, p2 away from G: their moment arm turns with the body, so the
    #: load carries two more columns, r x p and r . p, from which the kernels take the moment
    #: cos(theta) (r x p) - sin(theta) (r . p) at each state (rbhyst.model.kinematics.turned_loads)
    follow: bool = False
    #: where ``follow``: the columns each force signal adds to the load, (r x e_k, r . e_k) in the
    #: plane (from ``point``), its components along the kernels' rotation axes in space
    #: (rbhyst.model.rotations: the kernels turn the arm r_p themselves); None: the plane's
    turning: dict[str, tuple[float, ...]] | None = None

    def __post_init__(self):
        if self.directions is None:
            object.__setattr__(self, "directions", load_directions(PLANE, self.point))
        if self.constant is None:
            n = len(next(iter(self.directions.values()))) if self.directions else 0
            object.__setattr__(self, "constant", (0.0,) * n)

    @property
    def n(self) -> int:
        """The number of generalized loads: the body's coordinates."""
        return len(self.constant)

    @property
    def width(self) -> int:
        """Columns of the load arrays: n, and r x p, r . p where the forces' arm turns (follow) in
        the plane, the forces' three components in space."""
        if not self.follow:
            return self.n
        return self.n + (len(next(iter(self.turning.values()))) if self.turning else 2)

    def _constant_row(self) -> np.ndarray:
        return np.concatenate([self.constant, np.zeros(self.width - self.n)])

    @property
    def has_support(self) -> bool:
        return self.ag1 is not None or self.ag2 is not None or self.ag3 is not None

    @property
    def has_forces(self) -> bool:
        """Whether external forces act on the body: a force or moment signal, or a constant load
        (the weight): without them ``forces`` is zero at every time."""
        return any(k in FORCE_SIGNALS for k in self.signals) or any(c != 0.0 for c in self.constant)

    @property
    def signals(self) -> dict[str, Signal]:
        return {k: s for k, s in (("ag1", self.ag1), ("ag2", self.ag2), ("p1", self.p1), ("p2", self.p2),
                                  ("m3", self.m3), ("ag3", self.ag3), ("p3", self.p3), ("m1", self.m1),
                                  ("m2", self.m2)) if s is not None}

    def acts_before(self, t_end: float) -> bool:
        """Whether any signal is non-zero somewhere in [0, t_end)."""
        return any(s.acts_before(t_end) for s in self.signals.values())

    def substeps(self, dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Compute steps per output step that follow every signal acting then: a record's
        samples, a sine's period or a pulse's shape over signals.POINTS_PER_FEATURE; outside a
        signal's span its shape costs nothing.

        Returns (bounds, nsub): output steps bounds[i] to bounds[i + 1] (step k runs from k dt
        to (k + 1) dt) take nsub[i] compute steps each; a few numbers however long the run.
        """
        from rbhyst.model.records import Series

        spans = []
        for s in self.signals.values():
            need = max(1, math.ceil(dt / s.step - 1e-9))
            # a record is linear between its samples: the compute nodes must hold every sample
            # (its step and start a whole number of compute steps), or the load the loop sees is
            # another, smoother record, an error no estimate of the step's can see
            align = record_alignment(dt, s.step, s.start) if isinstance(s, Series) else 1
            if need == 1 and align == 1:
                continue
            # one step more on either side: the coarse steps next to the span then see none of
            # it (an analytic signal's node values are hat averages, see load_nodes)
            first = max(0, math.floor(s.start / dt) - 1)
            last = n_steps if s.end is None else min(n_steps, math.ceil(s.end / dt) + 1)
            if first < last:
                spans.append((first, last, need, align))
        # (sorted(set()) rather than np.unique, which imports numpy.ma: a command's every millisecond)
        bounds = np.array(sorted({0, n_steps, *(f for f, *_ in spans), *(l for _, l, *_ in spans)}), dtype=np.int64)
        need_of = np.ones(len(bounds) - 1, dtype=np.int64)
        align_of = np.ones(len(bounds) - 1, dtype=np.int64)
        for first, last, need, align in spans:
            inside = (bounds[:-1] >= first) & (bounds[1:] <= last)
            need_of[inside] = np.maximum(need_of[inside], need)
            align_of[inside] = np.lcm(align_of[inside], align)
        # the fewest compute steps that follow every signal and hold every record's samples
        nsub = align_of * -(-need_of // align_of)
        return bounds, nsub

    def support(self, t: np.ndarray, axes=(1, 2)) -> np.ndarray:
        """(n, len(axes)) support acceleration along the axes x_k, each signal's value at t (at a
        jump, that of its span)."""
        out = np.zeros((len(t), len(axes)))
        for c, k in enumerate(axes):
            s = self.signals.get(f"ag{k}")
            if s is not None:
                out[:, c] = s(t)
        return out

    def forces(self, t: np.ndarray) -> np.ndarray:
        """(n, len(q)) the generalized external forces on the body at t, support motion left out: the
        constant load (the weight, held by the static preload) and (p1, p2, p3) (eq. 13); at a
        jump, each signal's value on its span (rows hold the pulse's side of its ends)."""
        forces = {k: s for k, s in self.signals.items() if k in FORCE_SIGNALS}
        return self._combine({k: s(t) for k, s in forces.items()}, len(t), None)

    def load(self, t: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """(n, len(q)) generalized load p = -M (ag1, ag2, 0) + (p1, p2, p3), eq. 13 for p3."""
        return self._combine({k: s(t) for k, s in self.signals.items()}, len(t), mass)

    def load_nodes(self, t: np.ndarray, h: float, mass: np.ndarray) -> np.ndarray:
        """(n, len(q)) load at the nodes t (spacing h) of a compute grid that interpolates it linearly.

        Records are linear between their samples and are taken at the nodes, and so is an
        analytic signal where it is smooth. Within a step of one of its breakpoints (where it
        starts, stops or has a corner) a node takes the signal's average under its hat function
        (weight 1 - |t - t_k| / h), so that the trapezoidal impulse over the steps around it is
        the signal's exact integral: a jump (a sawtooth's end, a sine stopping at a non-zero
        value) falls wherever it falls and never costs an order of accuracy.
        """
        values = {}
        for k, s in self.signals.items():
            v = s(t)
            record = isinstance(s, Series)
            breaks = record_jumps(s) if record else s.breakpoints
            near = np.zeros(len(t), dtype=bool)
            for b in breaks:
                if b > 0.0:  # a signal that starts with the analysis starts at its right limit
                    near |= np.abs(t - b) < h
            if near.any():
                v[near] = signals.hat_average(RecordEdges(s, breaks, h) if record else s, t[near], h)
            values[k] = v
        return self._combine(values, len(t), mass)

    def weights(self, mass: np.ndarray | None) -> dict[str, np.ndarray]:
        """How a unit of each signal enters the generalized load: -M r for a support acceleration
        along the influence vector r ((-m, 0, 0) for ag1 in the plane), the generalized force of
        a unit force or moment ((1, 0, -x2P), (0, 1, x1P), (0, 0, 1) for p1, p2, m3: eq. 13).
        Without ``mass``, the forces only."""
        out = {}
        arm = {}
        if self.follow and self.turning is not None:
            arm = self.turning
        elif self.follow:  # (the plane body's: exact kinematics)
            x1, x2 = self.point
            arm = {"p1": (-x2, x1), "p2": (x1, x2)}  # (r x e_k, r . e_k) of a unit force at the point
        for k, r in self.directions.items():
            if k.startswith("ag"):
                if mass is not None:
                    # -M r for a diagonal M, with the zeros of r kept as +0.0
                    out[k] = np.array([-m * x if x != 0.0 else 0.0 for m, x in zip(mass, r)])
            else:
                out[k] = np.array(r, dtype=float)
            if self.follow and k in out:
                out[k] = np.concatenate([out[k], arm.get(k, (0.0,) * (self.width - self.n))])
        return out

    def analytic_table(self, mass: np.ndarray) -> np.ndarray:
        """(signals, ROW_SIZE + n): every analytic signal as a row of signals.ROW_SIZE floats and
        its n weights into the load, for compiled code that evaluates them exactly."""
        w = self.weights(mass)
        rows = [s.row() + list(w[k]) for k, s in self.signals.items() if not isinstance(s, Series)]
        return np.array(rows, dtype=float).reshape(-1, signals.ROW_SIZE + self.width)

    def record_pieces(self, brk: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """(pieces, 2, n) the constant load and the records' share of it at both ends of every
        piece brk[k]..brk[k + 1], each end's value seen from inside the piece (a record is zero
        before its first sample and after its last: a piece outside it sees zero). The
        records are linear between their samples: with the samples among the breakpoints,
        linear pieces are exact."""
        ta, tb = brk[:-1], brk[1:]
        out = np.empty((len(ta), 2, self.width))
        out[:] = self._constant_row()
        w = self.weights(mass)
        for k, s in self.signals.items():
            if isinstance(s, Series):
                out[:, 0, :] += np.where(ta < s.end, s(ta), 0.0)[:, None] * w[k]
                out[:, 1, :] += np.where(tb > s.start, s(tb), 0.0)[:, None] * w[k]
        return out

    def _combine(self, values: dict[str, np.ndarray], n: int, mass: np.ndarray | None) -> np.ndarray:
        p = np.empty((n, self.width))
        p[:] = self._constant_row()
        w = self.weights(mass)
        for k, v in values.items():
            for c in range(self.width):
                if w[k][c] != 0.0:
                    p[:, c] += w[k][c] * v
        return p


#: the signals that act on the body as external forces (not support motion)
FORCE_SIGNALS = ("p1", "p2", "m3", "p3", "m1", "m2")


def load_directions(coordinates, point=(0.0, 0.0)) -> dict[str, tuple[float, ...]]:
    """How each signal enters the generalized loads of a body with these coordinates
    (Excitation.directions): a support acceleration ag_k along x_k moves every coordinate by its
    influence vector r (the unit vector of the translation along x_k: the body moves with the
    support), a force p_k at ``point`` (from G) loads q by the k-th row of the point's
    kinematics T (u_P = T q, eqs. 7-8), p = T^T F (eq. 13), and a moment m_k the rotation about x_k."""
    n = len(coordinates)
    t = point_matrix(point, coordinates)
    out = {}
    for r, i in enumerate(translations(coordinates)):
        k = coordinates[i].axis
        unit = [0.0] * n
        unit[i] = 1.0
        out[f"ag{k}"] = tuple(unit)
        out[f"p{k}"] = tuple(float(x) for x in t[r])
    for j, c in enumerate(coordinates):
        if c.rotation:
            unit = [0.0] * n
            unit[j] = 1.0
            out[f"m{c.axis}"] = tuple(unit)
    return out


@dataclass(frozen=True)
class Element:
    """One [[elements]] entry as the user wrote it, or one direction of an [[isolators]] entry;
    ``row`` is its row in the kernel arrays."""

    x: tuple[float, ...]  # attachment point relative to G, m (three coordinates in space)
    angle_deg: float | None  # in the plane; None in space
    hysteresis: str
    count: int
    row: int
    stroke: tuple[float, float] | None = None  # (lower, upper) deformation it can take, m
    direction: tuple[float, float, float] | None = None  # in space: the unit line of action
    #: the [[isolators]] entry it is a direction of (1-based), and which: "axial", "shear1",
    #: "shear2" in space, "axial", "shear" in the plane; None for an [[elements]] entry
    isolator: int | None = None
    role: str | None = None
    #: where it is in the deck: "elements[3]" or "isolators[2] shear1"
    label: str = ""
    #: (lower, upper, K, e): a stop met at the deformations lower < 0 < upper (rbhyst.model.stop)
    stop: tuple[float, float, float, float] | None = None

    @property
    def line(self) -> str:
        """Its line of action as a user reads it: '90 deg' in the plane, '(0, 0, 1)' in space."""
        if self.direction is None:
            return f"{self.angle_deg:g} deg"
        return "(" + ", ".join(f"{d + 0.0:.4g}" for d in self.direction) + ")"


@dataclass(frozen=True)
class Damper:
    """One [[dampers]] entry: a linear viscous damper along ``angle_deg`` at x (relative to G)."""

    x: tuple[float, ...]
    angle_deg: float | None  # in the plane; None in space
    c: float  # N s/m, each
    count: int
    b: tuple[float, ...]  # its deformation is b . q (eqs. 5-8), its force acts back as b f
    direction: tuple[float, float, float] | None = None  # in space: the unit line of action


@dataclass(frozen=True)
class RayleighDamping:
    """C = a0 M + a1 K0 from the damping ratios at two circular frequencies of the initial system."""

    a0: float  # 1/s
    a1: float  # s
    frequencies_hz: tuple[float, float]  # where the ratios are met
    ratios: tuple[float, float]
    modes: tuple[int, int] | None  # the modes those are, when the deck named modes
    mode_frequencies_hz: tuple[float, ...]  # every mode of (M, K0), ascending
    matrix: np.ndarray  # (n, n)

    def ratio_at(self, f_hz) -> np.ndarray:
        """zeta(omega) = a0 / (2 omega) + a1 omega / 2."""
        w = 2.0 * np.pi * np.asarray(f_hz, dtype=float)
        return self.a0 / (2.0 * w) + self.a1 * w / 2.0

    def summary(self) -> dict:
        return {"a0_1_s": self.a0, "a1_s": self.a1, "frequencies_hz": list(self.frequencies_hz),
                "ratios": list(self.ratios), **({"modes": list(self.modes)} if self.modes else {}),
                "mode_frequencies_hz": list(self.mode_frequencies_hz),
                "mode_ratios": [float(z) for z in self.ratio_at(self.mode_frequencies_hz)],
                "stiffness": "K0 = sum k0 b b^T, the initial system's (elements' k0)"}


def mode_frequencies(mass: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Circular frequencies of M x'' + K x = 0 (M diagonal), ascending."""
    s = 1.0 / np.sqrt(mass)
    lam = np.linalg.eigvalsh(s[:, None] * k * s[None, :])
    return np.sqrt(np.clip(lam, 0.0, None))


def rayleigh_damping(spec: "dk.Rayleigh", mass: np.ndarray, k0: np.ndarray) -> RayleighDamping:
    """a0, a1 from zeta_i = a0 / (2 w_i) + a1 w_i / 2 at the two frequencies (InputError naming
    the deck key where they cannot be met)."""
    w_modes = mode_frequencies(mass, k0)
    f_modes = tuple(float(w / (2.0 * np.pi)) for w in w_modes)
    if spec.modes is not None:
        w = [w_modes[m - 1] for m in spec.modes]
        bad = [m for m, x in zip(spec.modes, w) if not x > 1e-12 * max(w_modes.max(), 1e-300)]
        if bad:
            raise InputError(f"damping.rayleigh.modes: mode {bad[0]} of the initial system has no stiffness "
                             "(zero frequency): give frequencies_hz")
    else:
        w = [2.0 * np.pi * f for f in spec.frequencies_hz]
    z = spec.ratios
    a = np.linalg.solve(np.array([[0.5 / w[0], 0.5 * w[0]], [0.5 / w[1], 0.5 * w[1]]]), np.array(z))
    a0, a1 = float(a[0]), float(a[1])
    if a0 < 0.0 or a1 < 0.0:
        # two ratios too different for the frequencies between them: a negative coefficient
        # would feed energy into some modes
        key = "modes" if spec.modes is not None else "frequencies_hz"
        raise InputError(f"damping.rayleigh.ratio: {list(z)} at {[round(x / (2 * np.pi), 6) for x in w]} Hz "
                         f"(damping.rayleigh.{key}) needs a0 = {a0:.4g}, a1 = {a1:.4g}: a negative coefficient "
                         "gives negative damping; bring the ratios closer")
    matrix = a0 * np.diag(mass) + a1 * k0
    return RayleighDamping(a0, a1, (float(w[0] / (2 * np.pi)), float(w[1] / (2 * np.pi))), tuple(map(float, z)),
                           tuple(spec.modes) if spec.modes is not None else None, f_modes, matrix)


@dataclass(frozen=True)
class System:
    """The rigid body on its elements: M q'' + C q' + R(q) = p(t) (seed eq. 11), q = (u1, u2, theta3).

    What the solve layer needs of a body is here as data: the number of coordinates n (the
    length of ``mass``), their names and units (``coordinates``), the element rows b_e (B,
    (ne, n)), the diagonal of M, the load's directions (``excitation.directions``) and a point's
    kinematics (:meth:`point_matrix`); no kernel assumes the plane.
    """

    title: str
    body: Body
    mass: np.ndarray  # (n,) the diagonal of M: diag(m, m, J), J about the mass centre G
    # kernel rows: elements with the same b and set deform alike and are evaluated once
    bvec: np.ndarray  # (ne, n) rows b_e = (cos a, sin a, x1 sin a - x2 cos a)
    mult: np.ndarray  # (ne,) how many identical elements each row stands for
    params: np.ndarray  # (ne, 2, 8) VRM sets
    k0: np.ndarray  # (ne,) elastic stiffness of each element: the K0 of the structure-dependent methods
    k_reversal: np.ndarray  # (ne,) stiffness at a reversal at u = 0 (the stiffest instant of a loop)
    elements: tuple[Element, ...]
    excitation: Excitation
    notes: tuple[str, ...] = field(default=())
    #: what the deck's magnitudes say of its units (rbhyst.model.plausible): a run's first warnings
    warnings: tuple[str, ...] = field(default=())
    dampers: tuple[Damper, ...] = field(default=())
    #: the weight m (g1, g2, 0) acting at G when the deck gives body.gravity
    weight: np.ndarray | None = None
    #: the static equilibrium under the weight (rbhyst.solve.static), once found: the run starts there
    static: object | None = None
    #: [damping.rayleigh]: C = a0 M + a1 K0, added to the dampers'
    rayleigh: RayleighDamping | None = None
    #: what q is: the names and units of the coordinates and of the columns they head
    coordinates: tuple[Coordinate, ...] = PLANE
    #: "small": the seed's kinematics (eqs. 7-8), u_e = b_e . q; "exact": a body point at r from
    #: G is at x_G + R(theta3) r for any rotation (rbhyst.model.kinematics)
    kinematics: str = "small"
    #: (ne,) each row's d_e . r_e, the offset of its body point along its line of action: with
    #: exact kinematics u_e = b1 u1 + b2 u2 + b3 sin(theta3) + c_e (cos(theta3) - 1); in space
    #: (6 ne + 3,): each row's point and line in the kernels' rotation axes, then the force
    #: point's (rbhyst.model.rotations.split_axial)
    axial: np.ndarray | None = None
    #: (n, n) orthogonal, or None (the identity): q in the deck's axes is ``frame @ q`` of the
    #: kernels. A body in space whose inertia tensor about G is not diagonal runs in its
    #: principal axes, where M is diagonal (rbhyst.model.space); its rows, loads and masses
    #: here are the kernels', and history.Layout writes every output in the deck's axes
    frame: np.ndarray | None = None

    def __post_init__(self):
        n = len(self.mass)
        sizes = {"coordinates": len(self.coordinates), "bvec columns": np.shape(self.bvec)[1],
                 "excitation loads": self.excitation.n}
        wrong = {k: v for k, v in sizes.items() if v != n}
        if wrong:
            raise ValueError(f"a System of {n} coordinates (mass) has {wrong}")
        if self.kinematics not in ("small", "exact"):
            raise ValueError(f"kinematics {self.kinematics!r}: 'small' or 'exact'")
        if self.kinematics == "exact" and self.axial is None:
            raise ValueError("exact kinematics need each row's axial offset (plane) or point and line (space)")

    @property
    def rotation_index(self) -> int:
        """Where theta3 sits in q when the kinematics are exact in the plane; -1 (small rotations)
        tells the compiled kernels to use the seed's linear rows u_e = b_e . q, -2 that the body
        is in space with exact kinematics (rbhyst.solve.kernels.layout SMALL, SPATIAL)."""
        if self.kinematics != "exact":
            return -1
        return 2 if self.coordinates == PLANE else -2

    @property
    def has_stops(self) -> bool:
        """Whether any element bears on a stop beyond a gap (rbhyst.model.stop)."""
        return any(el.stop is not None for el in self.elements)

    @property
    def kernel_params(self) -> np.ndarray:
        """The kernels' parameters: ``params`` (ne, 2, 8), and where an element has a stop a third
        row each (rbhyst.model.stop.STOP_ROW: lower and upper gap, K, e; +-inf, 0, 1 without)."""
        if not self.has_stops:
            return np.ascontiguousarray(self.params, dtype=float)
        from rbhyst.model.hysteresis import STOP_E, STOP_K, STOP_LOWER, STOP_UPPER

        out = np.zeros((len(self.params), 3, self.params.shape[2]))
        out[:, :2] = self.params
        out[:, 2, STOP_LOWER], out[:, 2, STOP_UPPER], out[:, 2, STOP_E] = -np.inf, np.inf, 1.0
        for el in self.elements:
            if el.stop is not None:
                out[el.row, 2, [STOP_LOWER, STOP_UPPER, STOP_K, STOP_E]] = el.stop
        return out

    @property
    def kernel_axial(self) -> np.ndarray:
        """(ne,) the rows' axial offsets for the kernels (zeros with small rotations, unused)."""
        return np.ascontiguousarray(self.axial if self.axial is not None else np.zeros(len(self.bvec)), dtype=float)

    @property
    def n(self) -> int:
        """The number of generalized coordinates."""
        return len(self.mass)

    def point_matrix(self, x) -> np.ndarray:
        """T(x) (translations, n): the motion of the body point x (m, from G) is T q (eqs. 7-8),
        q in the kernels' coordinates (the deck's unless the body turned to its principal axes)."""
        t = point_matrix(x, self.coordinates)
        return t if self.frame is None else t @ self.frame

    def to_deck(self, q: np.ndarray) -> np.ndarray:
        """(..., n) coordinates (or generalized forces: the frame is orthogonal) of the kernels in
        the deck's axes."""
        return q if self.frame is None else np.asarray(q) @ self.frame.T

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
    def C(self) -> np.ndarray:
        """Viscous damping matrix (n, n): sum count c b b^T of the dampers, plus Rayleigh's (zeros without)."""
        c = np.zeros((self.n, self.n))
        for dp in self.dampers:
            b = np.asarray(dp.b)
            c += dp.count * dp.c * np.outer(b, b)
        if self.rayleigh is not None:
            c += self.rayleigh.matrix
        return c

    @property
    def kernel_damping(self) -> np.ndarray:
        """C for the kernels: (n, n), and with exact kinematics two more rows per damper, its row
        at rest and its offset along its line (the plane: (b1, b2, b3), (c, c count, 0)) or its
        line and point in the kernels' axes (space: (d, x'), (d', c count, 0, 0)), from which the
        kernels turn its row with the body (rbhyst.solve.kernels.elements.turned_dampers)."""
        c = self.C
        if self.kinematics != "exact" or not self.dampers:
            return c
        rows = []
        p = np.eye(3) if self.frame is None else np.asarray(self.frame)[3:, 3:]
        for dp in self.dampers:
            total = dp.c * dp.count
            if dp.direction is None:
                rows += [list(dp.b), [axial_offset(dp.x[0], dp.x[1], math.radians(dp.angle_deg)), total, 0.0]]
            else:
                d = np.asarray(dp.direction, dtype=float)
                rows += [[*d, *(p.T @ np.asarray(dp.x, dtype=float))], [*(p.T @ d), total, 0.0, 0.0]]
        return np.vstack([c, np.array(rows, dtype=float)])

    @property
    def damper_b(self) -> np.ndarray:
        """(dampers, n) each damper's b, count expanded (CSV order)."""
        return np.array([dp.b for dp in self.dampers for _ in range(dp.count)]).reshape(-1, self.n)

    @property
    def damper_c(self) -> np.ndarray:
        return np.array([dp.c for dp in self.dampers for _ in range(dp.count)])

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


def axial_offset(x1: float, x2: float, angle_rad: float) -> float:
    """d . r for an element at r = (x1, x2) from G along d = (cos a, sin a): with exact
    kinematics, what the rotation's cos(theta3) - 1 multiplies in its deformation."""
    return x1 * math.cos(angle_rad) + x2 * math.sin(angle_rad)


def free_directions(bvec: np.ndarray, body: Body) -> list[str]:
    """Describe each rigid motion q != 0 with B^T q = 0: no element resists it."""
    size = body.extent or 1.0
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
                out.append("rotation about the mass centre G")
            else:
                g = body.mass_centre  # the user's frame, not G's
                out.append(f"rotation about the point ({c1 + g[0] + 0.0:.6g}, {c2 + g[1] + 0.0:.6g}) m")
    return out


#: an element attached farther from G than this many body sizes is worth a note
FAR_ELEMENT = 3.0
#: a body larger than this (m) is worth a note: were its vertices given in mm?
LARGE_BODY_M = 50.0


def implausible_geometry(body, elements) -> list[str]:
    """Notes on geometry that may be intended but is more often a slip: elements far from the body,
    a body the size of a building (vertices in mm?); in the plane or in space."""
    notes = []
    size = body.extent
    g = body.mass_centre
    if size > LARGE_BODY_M:
        notes.append(f"body: it reaches {size:.4g} m from its mass centre: are the vertices in mm? "
                     "(rbhyst takes every length in m)")
    for k, el in enumerate(elements, start=1):
        r = math.hypot(*el.x)
        if r > FAR_ELEMENT * size:
            where = ", ".join(f"{x + c:.4g}" for x, c in zip(el.x, g))
            notes.append(f"{el.label or f'elements[{k}]'}: attached at ({where}) m, {r:.4g} m from the mass centre: "
                         f"{r / size:.3g} times the body's size ({size:.4g} m)")
    return notes


def _signal(spec, scale_units: dict[str, float], base: Path,
            notes: list[str]) -> tuple[Signal, float | None]:
    """A callable of time in SI units and the signal's own end; what the run should say about
    the signal goes to ``notes``."""
    if isinstance(spec, dk.Random):
        series = random_series(spec, base)
        from rbhyst.model.random_vibration import said

        notes.append(said(series.tolerance))
        return series, series.duration
    factor = scale_units[spec.units]
    if isinstance(spec, dk.Sine):
        s = signals.sine(spec.amplitude * factor, spec.frequency_hz, spec.phase_deg, spec.start, spec.cycles,
                         spec.ramp_cycles)
        return s, s.end
    if isinstance(spec, dk.Pulse):
        if spec.type == "trapezoid" or spec.compensation != "none":  # as samples (shock_pulses)
            from rbhyst.model.shock_pulses import classical_pulse

            series = classical_pulse(spec.type, spec.amplitude * factor, spec.duration, spec.start,
                                     spec.compensation, spec.compensation_ratio, spec.rise).series
            return series, series.duration
        s = signals.Pulse(spec.type, spec.amplitude * factor, spec.duration, spec.start)
        return s, s.end
    path = Path(spec.file)
    if not path.is_absolute():
        path = base / path
    record = read_record(path, spec.dt)
    check_declared(record.declared, spec.units)  # the file's own word on its units must agree
    notes.extend(record.notes)
    if record.series.t0 > 0.0:
        notes.append(f"{path.name}: its time column starts at {record.series.t0:g} s: the support is at rest (zero "
                     f"acceleration) before it, as the analysis starts at 0 s with every signal; shift the "
                     f"file's times if it should start at 0")
    series = ScaledSeries(record.series.t0, record.series.dt, record.series.values * factor * spec.scale,
                          of=record.series, factor=factor * spec.scale)
    return series, series.duration


@dataclass(frozen=True)
class RandomSeries(Series):
    """Random vibration's samples, and their check against the standard's tolerances
    (rbhyst.model.random_vibration.tolerance, of the history before ``scale``)."""

    tolerance: dict = field(default_factory=dict)


def random_series(spec: "dk.Random", base: Path) -> Series:
    """Random vibration made once into samples (cached per process), from then on a record."""
    from rbhyst.model.random_vibration import cached_history, default_ramp, load_psd, size_problems, tolerance

    psd = load_psd(spec.psd, spec.units, base)
    problems = size_problems(psd, spec.duration, spec.dt, "")
    if problems:  # (the caller puts the signal's place in front)
        raise InputError([p.lstrip(".") for p in problems])
    key = (tuple(map(float, psd.frequency_hz)), tuple(map(float, psd.value)))
    ramp = default_ramp(spec.duration) if spec.ramp is None else float(spec.ramp)
    step, values = cached_history(key, float(spec.duration), int(spec.seed), spec.dt, ramp, spec.clip_sigma)
    return RandomSeries(0.0, step, values * spec.scale if spec.scale != 1.0 else values,
                        tolerance(values, step, psd, ramp))


class _Signals:
    """An excitation's signals read one by one (paths against ``base``): what each said goes to
    ``notes`` under its key, every problem is kept with its key until :meth:`check`."""

    def __init__(self, base: Path, notes: list[str]):
        self.base, self.notes = base, notes
        self.read: dict[str, Signal] = {}
        self.durations: list[float] = []
        self.problems: list[str] = []

    def add(self, name: str, spec, units, loc: str) -> None:
        if spec is None:
            return
        said: list[str] = []
        try:
            signal, duration = _signal(spec, units, self.base, said)
        except InputError as err:
            self.problems.extend(f"{loc}: {p}" for p in err.problems)
            return
        self.notes.extend(f"{loc}: {n}" for n in said)
        self.read[name] = signal
        if duration is not None:
            self.durations.append(duration)

    @property
    def duration(self) -> float | None:
        """Of the longest record or finite pulse."""
        return max(self.durations) if self.durations else None

    def check(self) -> None:
        if self.problems:
            raise InputError(self.problems)


def _excitation(deck: dk.Deck, base: Path, body: Body, notes: list[str]) -> Excitation:
    ex = deck.excitation
    if ex is None:
        return Excitation()
    signals = _Signals(base, notes)
    add = signals.add

    if ex.support is not None:
        add("ag1", ex.support.x1, dk.ACCEL_UNITS, "excitation.support.x1")
        add("ag2", ex.support.x2, dk.ACCEL_UNITS, "excitation.support.x2")
    point = (0.0, 0.0)
    if ex.force is not None:
        add("p1", ex.force.p1, dk.FORCE_UNITS, "excitation.force.p1")
        add("p2", ex.force.p2, dk.FORCE_UNITS, "excitation.force.p2")
        add("m3", ex.force.m3, dk.MOMENT_UNITS, "excitation.force.m3")
        if ex.force.point is None:
            if ex.force.p1 is not None or ex.force.p2 is not None:
                g = body.mass_centre
                notes.append(f"excitation.force.point is not given: p1 and p2 act at the mass centre G "
                             f"({g[0]:.6g}, {g[1]:.6g}) m")
        else:
            # the point is given in the deck's frame; loads act about G
            point = (ex.force.point[0] - body.mass_centre[0], ex.force.point[1] - body.mass_centre[1])
    signals.check()
    return Excitation(point=point, duration=signals.duration, **signals.read)


def space_turning(p: np.ndarray) -> dict[str, tuple[float, ...]]:
    """Excitation.turning of a body in space whose kernels' rotation axes are the columns of p:
    each force signal's components along them (the kernels turn its arm)."""
    return {k: tuple(float(v) for v in p.T[:, i]) for i, k in enumerate(("p1", "p2", "p3"))}


def arm_turns(excitation: Excitation) -> bool:
    """Whether p1, p2 (or p3) act away from G: with exact kinematics their moment arm turns with the body."""
    return any(abs(x) > 0.0 for x in excitation.point) and any(
        getattr(excitation, k) is not None for k in ("p1", "p2", "p3"))


def _kernel_rows(deck: dk.Deck, body: Body, exact: bool):
    """The elements as kernel rows: (rows b_e, their axial offsets, set names, multiplicities,
    the Element entries in deck order). An element that deforms exactly like another with the
    same set shares its row: the seed's shear isolators under P1 and P2 share b = (0, 1, x1)."""
    xs, bs = [], []
    entries = deck.element_entries
    for el, _ in entries:
        x = body.vertex(el.part, el.vertex) if el.vertex is not None else np.asarray(el.point, float) - body.mass_centre
        xs.append(x)
        bs.append(b_vector(x[0], x[1], math.radians(el.angle_deg)))
    b_all = np.array(bs)
    # with exact kinematics two elements deform alike only if their points also lie alike along
    # their line of action (d . r): the seed's shear isolators under P1 and P2 then part
    c_all = np.array([axial_offset(x[0], x[1], math.radians(el.angle_deg)) for x, (el, _) in zip(xs, entries)])
    firsts, row_of = _row_groups(np.column_stack([b_all, c_all]) if exact else b_all, deck)
    rows = [b_all[f] for f in firsts]
    axial = np.array([c_all[f] for f in firsts])
    names = [entries[f][0].hysteresis for f in firsts]
    mult = [0] * len(rows)
    elements = []
    for i, (el, origin) in enumerate(entries):
        row = int(row_of[i])
        mult[row] += el.count
        elements.append(Element((float(xs[i][0]), float(xs[i][1])), el.angle_deg, el.hysteresis, el.count, row,
                                el.stroke_limits, **_origin(origin), **_stop_of(el)))
    return rows, axial, names, mult, elements


def _stop_of(el) -> dict:
    """An Element's ``stop`` key for a deck element with one (rbhyst.model.deck.Stop.law)."""
    stop = getattr(el, "stop", None)
    return {} if stop is None else {"stop": stop.law}


def _origin(origin) -> dict:
    """An Element's keys for where it comes from (rbhyst.model.isolators.Origin)."""
    return {"isolator": origin.isolator, "role": origin.role, "label": origin.label}


def _row_groups(keyed: np.ndarray, deck: dk.Deck) -> tuple[list[int], np.ndarray]:
    """Elements whose rows ``keyed`` (one per element) round alike at 1e-12 and whose sets are
    the same share a kernel row (a pair split only costs time): (each row's first element, in
    the order of their first elements; each element's row)."""
    key = np.round(keyed / 1e-12).astype(np.int64)
    set_ids = {name: i for i, name in enumerate(deck.hysteresis)}
    for el in deck.all_elements:  # (the springs' sets of MSS isolators, after the deck's)
        set_ids.setdefault(el.hysteresis, len(set_ids))
    # (a dictionary of the keys: numpy's unique of rows went through a sort of a structured
    # view, a tenth of a sweep case's assembly for a few elements)
    rows: dict[tuple, int] = {}
    firsts: list[int] = []
    row_of = np.empty(len(key), dtype=int)
    for i, (k, el) in enumerate(zip(key.tolist(), deck.all_elements)):
        # (elements with different stops part: a stop's state is its row's)
        stop = None if getattr(el, "stop", None) is None else el.stop.law
        row = rows.setdefault((*k, set_ids[el.hysteresis], stop), len(firsts))
        if row == len(firsts):
            firsts.append(i)
        row_of[i] = row
    return firsts, row_of


def _set_stiffnesses(deck: dk.Deck) -> tuple[dict, dict, dict]:
    """Each hysteresis set as its array, its stiffness at a reversal at u = 0 (InputError where
    it is not positive) and k0, the larger slope of its limiting curves at u = 0."""
    sets = {name: hs.array() for name, hs in deck.hysteresis.items()}
    sets.update(_mss_sets(deck, sets))
    k_rev, k_el = {}, {}
    if deck.contacts:
        # a contact's element has no force of its own: its stop bears it (dk.Contact.element)
        sets[dk.CONTACT_SET] = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]] * 2)
        k_rev[dk.CONTACT_SET] = k_el[dk.CONTACT_SET] = 0.0
    for name, p in sets.items():
        if name == dk.CONTACT_SET:
            continue
        k, k_el[name], _ = stiffnesses_at_zero(p)
        if not k > 0.0:
            raise InputError(f"hysteresis.{name}: the stiffness at a reversal at u = 0 is {k:.6g} N/m; it must be > 0")
        k_rev[name] = k
    return sets, k_rev, k_el


def _mss_sets(deck: dk.Deck, sets: dict) -> dict:
    """The springs' sets of the deck's MSS isolators (rbhyst.model.mss.spring_set), by the names
    their elements give (InputError where a set with an exponential term has no reference)."""
    if not any(iso.coupling == "mss" for iso in deck.isolators or []):
        return {}
    from rbhyst.model.isolators import mss_set_name
    from rbhyst.model.mss import DEFAULT_SPRINGS, spring_set

    out, problems = {}, []
    for k, iso in enumerate(deck.isolators or [], start=1):
        if iso.coupling != "mss" or not (iso.hysteresis.shear or iso.hysteresis.shear1) in sets:
            continue
        name = iso.hysteresis.shear or iso.hysteresis.shear1
        n = iso.springs or DEFAULT_SPRINGS
        try:
            out[mss_set_name(name, n, iso.reference)] = spring_set(sets[name], n, iso.reference)
        except ValueError:
            problems.append(f"isolators[{k}].reference: required with coupling = \"mss\" and set {name!r}, which "
                            "has an exponential term (beta1, beta2): the largest shear deformation the scene "
                            "reaches (m), where the springs' force matches the set's")
    if problems:
        raise InputError(problems)
    return out


def stiffnesses_at_zero(p: np.ndarray) -> tuple[float, float, float]:
    """A set's stiffnesses at u = 0 ((2, 8) parameters): at a reversal, k0 (the larger slope of
    its limiting curves, at least 0) and the virgin tangent (the stiffer of its two first moves,
    eq. 16). Of its numbers alone, worked out once per process for each set: a sweep's cases
    share their sets."""
    return _set_stiffnesses_of(tuple(p.ravel().tolist()))


@functools.lru_cache(maxsize=1024)
def _set_stiffnesses_of(params: tuple[float, ...]) -> tuple[float, float, float]:
    p = np.array(params, dtype=float).reshape(2, -1)
    k_rev = float(reversal_stiffness(p, 0.0))
    k0 = max(float(limiting_slope(p, 1, 0.0)), float(limiting_slope(p, -1, 0.0)), 0.0)
    return k_rev, k0, max(virgin_tangent(p, 1.0), virgin_tangent(p, -1.0))


def _system(deck: dk.Deck, body, mass, rows, names, mult, elements, excitation, notes, dampers, weight,
            stiffnesses, **extra) -> System:
    """The System of rows built by either assembly: the sets per row (``stiffnesses``: what
    _set_stiffnesses gives), Rayleigh damping from their K0 where the deck asks for it, and
    ``extra`` (kinematics, frame, coordinates)."""
    sets, k_rev, k_el = stiffnesses
    with np.errstate(divide="ignore", over="ignore"):
        inverse = 1.0 / np.asarray(mass, dtype=float)
    if not np.all(np.isfinite(inverse) & (inverse > 0)):
        # (a positive mass the deck allows, 5e-324 kg, whose inverse overflows: M^-1 is every step's)
        key = "body.parts" if deck.body.parts else "body.inertia" if deck.body.inertia is not None else "body.mass"
        raise InputError(f"{key}: the body's mass matrix has entries {', '.join(f'{m:.3g}' for m in mass)} "
                         "(kg, kg m2): too small to divide by; check the deck's mass and units")
    bvec = np.array(rows)
    rayleigh = None
    if deck.damping is not None and deck.damping.rayleigh is not None:
        k0 = (bvec.T * (np.array(mult, dtype=float) * np.array([k_el[n] for n in names]))) @ bvec
        rayleigh = rayleigh_damping(deck.damping.rayleigh, mass, k0)
    from rbhyst.model import plausible

    spin = mass[2:] if len(mass) == 3 else mass[3:]  # (the plane's J; in space the principal moments)
    cautions = plausible.excitation_warnings(excitation, plausible.signal_units(deck), float(mass[0]),
                                             float(np.max(spin)), body.extent)
    cautions += plausible.density_warning(body.mass, plausible.body_measure(body), getattr(body, "dimensions", 2))
    cautions += plausible.random_warnings(excitation)
    return System(
        title=deck.title or "",
        warnings=tuple(cautions),
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
        dampers=tuple(dampers),
        weight=weight,
        rayleigh=rayleigh,
        **extra,
    )


def _check_sections(deck: dk.Deck, run: bool) -> None:
    """A run needs a body, elements and an analysis (dk.check_runnable); the modes the first two."""
    if run:
        dk.check_runnable(deck)
        return
    missing = [f"{key}: required for the body's modes" for key, there in (("body", deck.body is not None),
                                                                          ("elements", deck.supports)) if not there]
    if missing:
        raise InputError(missing)


def assemble(deck: dk.Deck, base: Path, run: bool = True) -> System:
    """Build the System of a runnable deck; relative file paths resolve against ``base``.
    ``run=False``: the body on its elements alone (what its modes need), without the excitation
    and without asking for an analysis section."""
    _check_sections(deck, run)
    if deck.body.dimensions == 3:
        return assemble_space(deck, base, run)
    body, notes = body_from_deck(deck.body)
    mass = np.array([body.mass, body.mass, body.inertia])
    stiffnesses = _set_stiffnesses(deck)  # (a set that cannot be an element says so before the elements do)

    exact = deck.analysis is not None and deck.analysis.kinematics == "exact"
    rows, axial, names, mult, elements = _kernel_rows(deck, body, exact)
    bvec = np.array(rows)
    notes.extend(implausible_geometry(body, elements))
    free = free_directions(bvec, body)
    if free:
        raise InputError(f"elements: the body is not restrained against {'; '.join(free)}")

    excitation = _excitation(deck, base, body, notes) if run else Excitation()
    dampers = []
    for dp in deck.dampers or []:
        x = body.vertex(dp.part, dp.vertex) if dp.vertex is not None else np.asarray(dp.point, float) - body.mass_centre
        b = b_vector(x[0], x[1], math.radians(dp.angle_deg))
        dampers.append(Damper((float(x[0]), float(x[1])), dp.angle_deg, dp.c, dp.count, tuple(map(float, b))))
    weight = None
    if deck.body.gravity is not None:
        weight = body.mass * np.array([deck.body.gravity[0], deck.body.gravity[1], 0.0])
    system = _system(deck, body, mass, rows, names, mult, elements, excitation, notes, dampers, weight,
                     stiffnesses, kinematics="exact" if exact else "small", axial=axial if exact else None)
    if exact and arm_turns(excitation):
        system = replace(system, excitation=replace(excitation, follow=True))
    return system


# ---------------------------------------------------------------- a body in space


def _excitation_space(deck: dk.Deck, base: Path, body, frame, notes: list[str]) -> Excitation:
    """The support motion along x1, x2, x3 and the forces p1..p3, moments m1..m3, with their loads
    in the kernels' axes."""
    from rbhyst.model.coordinates import SPACE
    from rbhyst.model.space import FORCE_KEYS, SUPPORT_KEYS

    ex = deck.excitation
    point = np.zeros(3)
    signals = _Signals(base, notes)
    add = signals.add

    if ex is not None and ex.support is not None:
        for name, axis in SUPPORT_KEYS.items():
            add(name, getattr(ex.support, axis), dk.ACCEL_UNITS, f"excitation.support.{axis}")
    if ex is not None and ex.force is not None:
        for name in FORCE_KEYS:
            add(name, getattr(ex.force, name), dk.FORCE_UNITS if name[0] == "p" else dk.MOMENT_UNITS,
                f"excitation.force.{name}")
        if ex.force.point is None:
            if any(getattr(ex.force, k) is not None for k in ("p1", "p2", "p3")):
                g = body.mass_centre
                notes.append("excitation.force.point is not given: p1, p2 and p3 act at the mass centre G "
                             f"({', '.join(f'{x:.6g}' for x in g)}) m")
        else:
            point = np.asarray(ex.force.point, dtype=float) - body.mass_centre
    signals.check()
    directions = load_directions(SPACE, tuple(point))
    if frame is not None:
        directions = {k: tuple(float(x) for x in frame.T @ np.array(v)) for k, v in directions.items()}
    return Excitation(point=tuple(float(x) for x in point), duration=signals.duration,
                      directions=directions, **signals.read)


def _placed_space(body, entry) -> np.ndarray:
    """The point of an element or damper entry, from G."""
    if entry.vertex is not None:
        return np.asarray(body.vertex(entry.part, entry.vertex), dtype=float)
    return np.asarray(entry.point, dtype=float) - body.mass_centre


def _kernel_rows_space(deck: dk.Deck, body, frame, exact: bool = False):
    """(rows in the kernels' axes, set names, multiplicities, Element entries in deck order, and
    with exact kinematics each row's point and line in the kernels' rotation axes (6 per row)):
    elements with the same row and set share it, as in the plane; with exact kinematics only
    where their points and lines are the same too (their deformations differ beyond first order)."""
    from rbhyst.model.space import row, unit

    p = np.eye(3) if frame is None else frame[3:, 3:]
    xs, bs, ds = [], [], []
    entries = deck.element_entries
    for el, _ in entries:
        x = _placed_space(body, el)
        d = unit(el.direction)
        b = row(x, d)
        xs.append(x)
        ds.append(d)
        bs.append(b if frame is None else frame.T @ b)
    b_all = np.array(bs)
    arms = np.column_stack([np.array(xs) @ p, np.array(ds) @ p])  # (x', d') = (P^T x, P^T d) per element
    firsts, row_of = _row_groups(np.column_stack([b_all, arms]) if exact else b_all, deck)
    rows = [b_all[f] for f in firsts]
    names = [entries[f][0].hysteresis for f in firsts]
    mult = [0] * len(rows)
    elements = []
    for i, (el, origin) in enumerate(entries):
        r = int(row_of[i])
        mult[r] += el.count
        elements.append(Element(tuple(float(v) for v in xs[i]), None, el.hysteresis, el.count, r, el.stroke_limits,
                                tuple(float(v) for v in ds[i]), **_origin(origin), **_stop_of(el)))
    return rows, names, mult, elements, np.concatenate([arms[f] for f in firsts])


def assemble_space(deck: dk.Deck, base: Path, run: bool = True) -> System:
    """The System of a deck in space (rbhyst.model.space: b = (d, r x d), the principal axes);
    ``assemble`` hands a deck in space over to it."""
    from rbhyst.model.coordinates import SPACE
    from rbhyst.model.solid import solid_from_deck
    from rbhyst.model.space import FORCE_KEYS, SUPPORT_KEYS, free_motions, principal_frame, row, unit

    exact = deck.analysis is not None and deck.analysis.kinematics == "exact"
    body, notes = solid_from_deck(deck.body)
    j_diag, frame = principal_frame(body.inertia)
    mass = np.concatenate([[body.mass] * 3, j_diag])
    stiffnesses = _set_stiffnesses(deck)  # (a set that cannot be an element says so before the elements do)
    rows, names, mult, elements, axial = _kernel_rows_space(deck, body, frame, exact)
    bvec = np.array(rows)
    notes.extend(implausible_geometry(body, elements))
    free = free_motions(bvec, body, frame)
    if free:
        raise InputError(f"elements: the body is not restrained against {'; '.join(free)}")
    excitation = _excitation_space(deck, base, body, frame, notes) if run else Excitation(
        directions=load_directions(SPACE), constant=(0.0,) * 6, point=(0.0, 0.0, 0.0))  # (the modes' alone)
    dampers = []
    for dp in deck.dampers or []:
        x = _placed_space(body, dp)
        d = unit(dp.direction)
        b = row(x, d)
        b = b if frame is None else frame.T @ b
        dampers.append(Damper(tuple(float(v) for v in x), None, dp.c, dp.count, tuple(map(float, b)),
                              tuple(float(v) for v in d)))
    weight = None
    if deck.body.gravity is not None:
        weight = np.concatenate([body.mass * np.asarray(deck.body.gravity, dtype=float), np.zeros(3)])
    if not exact:
        return _system(deck, body, mass, rows, names, mult, elements, excitation, notes, dampers, weight,
                       stiffnesses, coordinates=SPACE, frame=frame)
    p = np.eye(3) if frame is None else frame[3:, 3:]
    axial = np.concatenate([axial, p.T @ np.asarray(excitation.point, dtype=float)])
    if arm_turns(excitation):  # forces away from G: their three components (rotation axes) follow
        excitation = replace(excitation, follow=True, turning=space_turning(p))
    return _system(deck, body, mass, rows, names, mult, elements, excitation, notes, dampers, weight,
                   stiffnesses, coordinates=SPACE, frame=frame, kinematics="exact", axial=axial)
