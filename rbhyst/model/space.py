"""Assemble a deck in space into a :class:`~rbhyst.model.system.System` of six coordinates.

q = (u1, u2, u3, theta1, theta2, theta3): the translations of the mass centre G and its small
rotations about the deck's axes (a vector, theta). A body point at r from G moves by
u + theta x r; an element along the unit direction d at r deforms by d . (u + theta x r) =
b . q with b = (d, r x d), and its force f acts back on the body as b f (force d f, moment
r x d f about G). M = diag(m, m, m, J) with J the inertia tensor about G.

The compiled kernels take a diagonal M. Where J is not diagonal the body runs in its principal
axes: J = P diag(Jp) P^T, the kernels' rotations phi = P^T theta, their rows b_phi = P^T b_theta
and loads likewise, and System.frame = diag(I, P) turns every output back (history.Layout):
small rotations about the deck's axes are a vector, so the change of axes is exact. Where J is
diagonal as given, P = I and nothing changes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.model import deck as dk
from rbhyst.model.coordinates import SPACE
from rbhyst.model.hysteresis import limiting_slope, reversal_stiffness
from rbhyst.model.solid import Solid, solid_from_deck
from rbhyst.model.system import (FAR_ELEMENT, LARGE_BODY_M, Damper, Element, Excitation, System, _signal,
                                 load_directions, rayleigh_damping)

#: the signals of a body in space and their deck keys
SUPPORT_KEYS = {"ag1": "x1", "ag2": "x2", "ag3": "x3"}
FORCE_KEYS = ("p1", "p2", "p3", "m1", "m2", "m3")


def row(x, direction) -> np.ndarray:
    """b = (d, r x d) of an element along ``direction`` (unit) at x (from G): its deformation is
    b . q, the motion of its point along d."""
    d = np.asarray(direction, dtype=float)
    return np.concatenate([d, np.cross(np.asarray(x, dtype=float), d)])


def unit(direction) -> np.ndarray:
    """The line of action, normalised (the deck has refused a zero vector)."""
    d = np.asarray(direction, dtype=float)
    return d / np.linalg.norm(d)


def principal_frame(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(the diagonal of J in the kernels' axes, the frame diag(I, P) or None where J is diagonal
    as given). P's columns are the principal axes, right-handed (det P = +1)."""
    j = np.asarray(inertia, dtype=float)
    if not np.any(j - np.diag(np.diag(j))):
        return np.diag(j).copy(), None
    lam, p = np.linalg.eigh(j)
    if np.linalg.det(p) < 0.0:
        p[:, 2] = -p[:, 2]
    frame = np.eye(6)
    frame[3:, 3:] = p
    return lam, frame


def free_motions(bvec: np.ndarray, body: Solid, frame: np.ndarray | None) -> list[str]:
    """Each rigid motion no element resists (B q = 0), described in the deck's axes."""
    size = body.extent or 1.0
    scale = np.array([1.0, 1.0, 1.0, 1.0 / size, 1.0 / size, 1.0 / size])
    _, sv, vt = np.linalg.svd(bvec * scale, full_matrices=True)
    sv = np.concatenate([sv, np.zeros(6 - len(sv))])
    out = []
    for k in range(6):
        if sv[k] > 1e-9 * max(sv[0], 1e-300):
            continue
        q = vt[k] * scale
        q = q if frame is None else frame @ q
        u, th = q[:3], q[3:]

        def vec(v):
            v = v / np.max(np.abs(v))
            return "(" + ", ".join(f"{x + 0.0:.4g}" for x in np.where(np.abs(v) < 1e-9, 0.0, v)) + ")"

        if np.linalg.norm(th) * size < 1e-9 * np.linalg.norm(u):
            out.append(f"translation along {vec(u)}")
        else:
            c = np.cross(th, u) / float(th @ th) + body.mass_centre  # the axis's point nearest G, deck frame
            out.append(f"rotation about the axis {vec(th)} through ({', '.join(f'{x + 0.0:.4g}' for x in c)}) m")
    return out


def _excitation(deck: dk.Deck, base: Path, body: Solid, frame, notes: list[str]) -> Excitation:
    """The support motion along x1, x2, x3 and the forces p1..p3, moments m1..m3, with their loads
    in the kernels' axes."""
    ex = deck.excitation
    point = np.zeros(3)
    sig, durations, problems = {}, [], []

    def add(name, spec, units, loc):
        if spec is None:
            return
        said: list[str] = []
        try:
            s, dur = _signal(spec, units, base, said)
        except InputError as err:
            problems.extend(f"{loc}: {p}" for p in err.problems)
            return
        notes.extend(f"{loc}: {n}" for n in said)
        sig[name] = s
        if dur is not None:
            durations.append(dur)

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
    if problems:
        raise InputError(problems)
    directions = load_directions(SPACE, tuple(point))
    if frame is not None:
        directions = {k: tuple(float(x) for x in frame.T @ np.array(v)) for k, v in directions.items()}
    return Excitation(point=tuple(float(x) for x in point), duration=max(durations) if durations else None,
                      directions=directions, **sig)


def _placed(body: Solid, entry) -> np.ndarray:
    """The point of an element or damper entry, from G."""
    if entry.vertex is not None:
        return np.asarray(body.vertex(entry.part, entry.vertex), dtype=float)
    return np.asarray(entry.point, dtype=float) - body.mass_centre


def _kernel_rows(deck: dk.Deck, body: Solid, frame):
    """(rows in the kernels' axes, set names, multiplicities, Element entries in deck order):
    elements with the same row and set share it, as in the plane."""
    xs, bs, ds = [], [], []
    for el in deck.elements:
        x = _placed(body, el)
        d = unit(el.direction)
        b = row(x, d)
        xs.append(x)
        ds.append(d)
        bs.append(b if frame is None else frame.T @ b)
    b_all = np.array(bs)
    key = np.round(b_all / 1e-12).astype(np.int64)
    set_ids = {name: i for i, name in enumerate(deck.hysteresis)}
    key = np.column_stack([key, [set_ids[el.hysteresis] for el in deck.elements]])
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    order = np.argsort(first)
    row_of = np.empty(len(first), dtype=int)
    row_of[order] = np.arange(len(first))
    rows = [b_all[first[k]] for k in order]
    names = [deck.elements[first[k]].hysteresis for k in order]
    mult = [0] * len(rows)
    elements = []
    for i, el in enumerate(deck.elements):
        r = int(row_of[inverse[i]])
        mult[r] += el.count
        elements.append(Element(tuple(float(v) for v in xs[i]), None, el.hysteresis, el.count, r, el.stroke_limits,
                                tuple(float(v) for v in ds[i])))
    return rows, names, mult, elements


def implausible(body: Solid, elements) -> list[str]:
    """Notes on geometry more often a slip than intended (as in the plane)."""
    notes = []
    size = body.extent
    g = body.mass_centre
    if size > LARGE_BODY_M:
        notes.append(f"body: it reaches {size:.4g} m from its mass centre: are the vertices in mm? "
                     "(rbhyst takes every length in m)")
    for k, el in enumerate(elements, start=1):
        r = float(np.linalg.norm(el.x))
        if r > FAR_ELEMENT * size:
            where = ", ".join(f"{x + c:.4g}" for x, c in zip(el.x, g))
            notes.append(f"elements[{k}]: attached at ({where}) m, {r:.4g} m from the mass centre: "
                         f"{r / size:.3g} times the body's size ({size:.4g} m)")
    return notes


def assemble_space(deck: dk.Deck, base: Path, run: bool = True) -> System:
    """The System of a deck in space (see the module docstring); the counterpart of
    rbhyst.model.system.assemble, which hands a deck in space over to it."""
    if deck.analysis is not None and deck.analysis.kinematics == "exact":
        raise InputError('analysis.kinematics: "exact" rotations are not built in for a 3-D body yet: use '
                         'kinematics = "small" (the default)')
    body, notes = solid_from_deck(deck.body)
    j_diag, frame = principal_frame(body.inertia)
    mass = np.concatenate([[body.mass] * 3, j_diag])
    sets = {name: hs.array() for name, hs in deck.hysteresis.items()}
    k_rev, k_el = {}, {}
    for name, p in sets.items():
        k = reversal_stiffness(p, 0.0)
        if not k > 0.0:
            raise InputError(f"hysteresis.{name}: the stiffness at a reversal at u = 0 is {k:.6g} N/m; it must be > 0")
        k_rev[name] = k
        k_el[name] = max(float(limiting_slope(p, 1, 0.0)), float(limiting_slope(p, -1, 0.0)), 0.0)
    rows, names, mult, elements = _kernel_rows(deck, body, frame)
    bvec = np.array(rows)
    notes.extend(implausible(body, elements))
    free = free_motions(bvec, body, frame)
    if free:
        raise InputError(f"elements: the body is not restrained against {'; '.join(free)}")
    excitation = _excitation(deck, base, body, frame, notes) if run else Excitation(
        directions=load_directions(SPACE), constant=(0.0,) * 6)
    dampers = []
    for dp in deck.dampers or []:
        x = _placed(body, dp)
        d = unit(dp.direction)
        b = row(x, d)
        b = b if frame is None else frame.T @ b
        dampers.append(Damper(tuple(float(v) for v in x), None, dp.c, dp.count, tuple(map(float, b)),
                              tuple(float(v) for v in d)))
    rayleigh = None
    if deck.damping is not None and deck.damping.rayleigh is not None:
        k0 = (bvec.T * (np.array(mult, dtype=float) * np.array([k_el[n] for n in names]))) @ bvec
        rayleigh = rayleigh_damping(deck.damping.rayleigh, mass, k0)
    weight = None
    if deck.body.gravity is not None:
        weight = np.concatenate([body.mass * np.asarray(deck.body.gravity, dtype=float), np.zeros(3)])
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
        dampers=tuple(dampers),
        weight=weight,
        rayleigh=rayleigh,
        coordinates=SPACE,
        frame=frame,
    )
