"""Natural frequencies and mode shapes of the body on its elements, undamped: of (M, K0), the
initial system (K0 = sum mult k0 b b^T, the stiffness the Rayleigh damping and the
structure-dependent methods take), and, where the deck gives gravity, of (M, Kt), Kt the same
sum with each element's tangent at the static equilibrium under the weight (rbhyst.solve.static).
Dampers and Rayleigh damping do not enter: they do not change the undamped modes.

The generalized symmetric eigenproblem K phi = omega^2 M phi (the Cholesky reduction
scipy.linalg.eigh makes, in numpy) for any number of coordinates; shapes in the order of q, scaled to a largest component of +1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rbhyst.solve.kernels.layout import K as TANGENT

INITIAL = "initial"
AT_REST = "tangent at rest under gravity"
#: the stiffnesses of rbhyst.model.effective a mode set may take at an amplitude
SECANT = "secant"
REVERSAL = "reversal"
#: an eigenvalue omega^2 within this fraction of the largest of zero is a rigid-body mode (0 Hz)
RIGID = 1e-10
#: frequencies this close (relative) are one repeated frequency: their shapes are one choice
REPEATED = 1e-9
#: shape components below this (the largest being 1) are rounding, written as 0
ROUNDING = 1e-12


@dataclass(frozen=True)
class Modes:
    """The modes of one stiffness: frequencies ascending (Hz), one shape per mode (n values in
    the order of ``coordinates``, largest component +1), and what the stiffness is."""

    coordinates: tuple[str, ...]
    frequencies_hz: tuple[float, ...]
    shapes: tuple[tuple[float, ...], ...]
    stiffness: str  # INITIAL, AT_REST or what amplitude_modes took
    notes: tuple[str, ...] = ()

    def summary(self) -> dict:
        """summary.json's form: coordinates, frequencies_hz, shapes, stiffness, notes if any."""
        return {"coordinates": list(self.coordinates), "frequencies_hz": list(self.frequencies_hz),
                "shapes": [list(s) for s in self.shapes], "stiffness": self.stiffness,
                **({"notes": list(self.notes)} if self.notes else {})}


def normalised(shape: np.ndarray) -> np.ndarray:
    """``shape`` scaled so that its largest component in absolute value is +1 (the first of
    those equal to rounding, so that the sign does not depend on it); rounding set to 0."""
    size = np.abs(shape)
    i = int(np.argmax(size >= (1.0 - 1e-9) * size.max()))
    out = shape / shape[i]
    out[np.abs(out) < ROUNDING] = 0.0
    return out + 0.0  # no -0.0


def generalized_eigh(k: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """K x = lambda M x, M symmetric positive definite: eigenvalues ascending and M-orthonormal
    eigenvectors (columns), by the Cholesky reduction M = L L^T, (L^-1 K L^-T) y = lambda y,
    x = L^-T y: what scipy.linalg.eigh(K, M) does (LAPACK sygv), in numpy alone (a run imports
    no scipy)."""
    low = np.linalg.cholesky(m)
    a = np.linalg.solve(low, np.linalg.solve(low, k).T)  # L^-1 K L^-T (symmetric: K is)
    lam, y = np.linalg.eigh(0.5 * (a + a.T))
    return lam, np.linalg.solve(low.T, y)


def modes_of(mass, stiffness, coordinates, kind: str = INITIAL) -> Modes:
    """The undamped modes of M q'' + K q = 0: ``mass`` the diagonal of M (n,) or M itself (n, n),
    ``stiffness`` K (n, n) symmetric, ``coordinates`` their names in the order of q.

    An eigenvalue within RIGID of the largest of zero is a rigid-body mode, 0 Hz with a note;
    a clearly negative one (a tangent that loses stiffness along the mode) is 0 Hz too, with a
    note saying so; repeated frequencies get a note (their shapes are one basis of many).
    """
    m = np.asarray(mass, dtype=float)
    m = np.diag(m) if m.ndim == 1 else m
    k = np.asarray(stiffness, dtype=float)
    k = 0.5 * (k + k.T)
    names = tuple(str(c) for c in coordinates)
    if k.shape != m.shape or len(names) != len(m):
        raise ValueError(f"modes: M {m.shape}, K {k.shape} and {len(names)} coordinates do not agree")
    lam, vec = generalized_eigh(k, m)
    top = max(float(np.max(np.abs(lam))), 0.0)
    notes = []
    freqs = []
    for j, x in enumerate(lam):
        if abs(x) <= RIGID * top or top == 0.0:
            notes.append(f"mode {j + 1}: a rigid-body motion no element resists (0 Hz)")
            freqs.append(0.0)
        elif x < 0.0:
            notes.append(f"mode {j + 1}: the stiffness is negative along it (omega^2 = {x:.4g} 1/s2): "
                         "no oscillation, the state is unstable (0 Hz)")
            freqs.append(0.0)
        else:
            freqs.append(float(np.sqrt(x) / (2.0 * np.pi)))
    for j in range(1, len(freqs)):
        a, b = freqs[j - 1], freqs[j]
        if b > 0.0 and b - a <= REPEATED * b:
            notes.append(f"modes {j} and {j + 1}: the same frequency; their shapes are one choice "
                         "among the combinations of the two")
    shapes = tuple(tuple(float(v) for v in normalised(vec[:, j])) for j in range(len(freqs)))
    return Modes(names, tuple(freqs), shapes, kind, tuple(notes))


def coordinate_names(system) -> tuple[str, ...]:
    """u1, u2, theta3 ...: the keys of the body's coordinates, in the order of q."""
    return tuple(c.key("d") for c in system.coordinates)


def element_stiffness(system, k: np.ndarray) -> np.ndarray:
    """B^T diag(mult k) B: the body's stiffness from one stiffness per element row."""
    return (system.bvec.T * (system.mult * np.asarray(k, dtype=float))) @ system.bvec


def initial_modes(system) -> Modes:
    """The modes of (M, K0): each element's k0, the slope of its limiting curves at u = 0."""
    return modes_of(*in_deck_axes(system, element_stiffness(system, system.k0)), coordinate_names(system), INITIAL)


def in_deck_axes(system, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) in the deck's axes: a body that runs in its principal axes (System.frame) has its
    shapes in the deck's coordinates, as every output."""
    frame = getattr(system, "frame", None)
    if frame is None:
        return system.mass, k
    return (frame * system.mass) @ frame.T, frame @ k @ frame.T


def amplitude_stiffness(system, amplitude: float, stiffness: str = SECANT) -> np.ndarray:
    """(ne,) each element row's stiffness on the steady symmetric cycle of ``amplitude`` m of its
    set (rbhyst.model.effective): its k_eff (secant) or its tangent just after a reversal. Every
    element at the same amplitude: the modes of a body that moves that much in its mounts."""
    from rbhyst.model.effective import effective

    if stiffness not in (SECANT, REVERSAL):
        raise ValueError(f"stiffness {stiffness!r}: {SECANT} or {REVERSAL}")
    found: dict[bytes, float] = {}
    out = np.empty(len(system.params))
    for row, p in enumerate(system.params):
        key = p.tobytes()  # (rows of one set share the cycle)
        if key not in found:
            cycle = effective(p, amplitude)
            found[key] = cycle.k_eff if stiffness == SECANT else cycle.k_reversal
        out[row] = found[key]
    return out


def amplitude_modes(system, amplitude: float, stiffness: str = SECANT) -> Modes:
    """The modes of (M, K(A)), K(A) = B^T diag(mult k(A)) B with :func:`amplitude_stiffness`."""
    k = element_stiffness(system, amplitude_stiffness(system, amplitude, stiffness))
    what = (f"effective (secant) stiffness at {amplitude:g} m" if stiffness == SECANT
            else f"tangent just after a reversal at {amplitude:g} m")
    return modes_of(*in_deck_axes(system, k), coordinate_names(system), what)


def tangent_at_rest(system) -> np.ndarray:
    """Kt = B^T diag(mult k_t) B, k_t each element row's tangent (eq. 16) at the static equilibrium
    (with exact kinematics, B at the equilibrium's rotation and the forces' geometric stiffness)
    under the weight, on the branch the weight loaded it along (an element it left undeformed: its
    virgin tangent, the larger of its two directions). The equilibrium is found here where the
    system does not carry it yet (AnalysisError where the elements cannot carry the weight)."""
    static = system.static
    if static is None:
        from rbhyst.solve.static import static_equilibrium

        static = static_equilibrium(system)
    if system.kinematics != "exact":
        return element_stiffness(system, static.st[:, TANGENT])
    # exact kinematics: the rows turned with the body, and the forces' geometric stiffness (the
    # weight's P-Delta) sum mult f d2u/dtheta2 on the rotation
    from rbhyst.model.kinematics import rows_at
    from rbhyst.solve.kernels.layout import F

    rot = system.rotation_index
    rows = rows_at(system.bvec, system.kernel_axial, rot, static.q)
    k = (rows.T * (system.mult * static.st[:, TANGENT])) @ rows
    if rot < 0:  # in space: d(x x R^T d')/d(turn) = -((x . a) I - a x^T), a = R^T d' (rbhyst.model.rotations)
        from rbhyst.model.rotations import matrices, split_axial

        x, c, _ = split_axial(system.kernel_axial, len(rows))
        a = c @ matrices(static.q[3:6])[0]  # rows: (R^T d')^T
        mf = system.mult * static.st[:, F]
        geo = -(np.einsum("e,ei,ei->", mf, x, a) * np.eye(3) - np.einsum("e,ei,ej->ij", mf, a, x))
        k[3:, 3:] += 0.5 * (geo + geo.T)
        return k
    th = float(static.q[rot])
    k[rot, rot] -= float(np.sum(system.mult * static.st[:, F] * (system.bvec[:, rot] * np.sin(th)
                                                                 + system.axial * np.cos(th))))
    return k


def at_rest_modes(system) -> Modes | None:
    """The modes of (M, Kt) at the static equilibrium under gravity; None without gravity."""
    if system.weight is None:
        return None
    return modes_of(*in_deck_axes(system, tangent_at_rest(system)), coordinate_names(system), AT_REST)


def modes_summary(system) -> dict:
    """summary.json's ``modes``: the initial system's, with ``at_rest`` where there is gravity."""
    out = initial_modes(system).summary()
    rest = at_rest_modes(system)
    if rest is not None:
        out["at_rest"] = rest.summary()
    return out
