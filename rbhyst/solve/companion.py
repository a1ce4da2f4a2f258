"""The error of a fixed-step run from its companion: one more run, not an adaptive solution.

A second-order method's nodes lie, to O(h^4), on the exact solution of a modified equation,

    M q'' + C q' + R(q) = p(t) + S,    S = O(h^2),

whose S follows from the method's formulas (below, with A = the method's acceleration at the
nodes, V its velocity; derivatives of A by differences of the nodes' values):

    newmark (average acceleration)   S = h^2 M A''/6 + h^2 C A'/12
    central difference               S = -h^2 M A''/12 - h^2 C A'/6
    chang (D = M + h/2 C + h^2/4 K0) S = -h^2 [M A''/12 + 5/12 C A' + K0 A/4 + C M^-1 (C A + K0 V)/4]

(eliminate V from the displacement and velocity updates and expand in h; the undamped linear
case gives each method's known period error). The run is the exact solution of the scene with
+S added; the same method on the scene with -S added (the *companion*) is the exact solution
to O(h^4) plus the same O(h^2) error of its own, which cancels. The difference of the two is the
run's error, through every yield and reversal, as the nonlinear run sees them.

One part of the error is not in S: the loop starts an element's new branch at the node where
its deformation turned, not at the turn (seed eq. 14), O(h^2) off, and every force along the
branch carries that until its memory fades. The companion's forces are therefore re-driven
along its deformation with each turn located within its step (rbhyst.solve.kernels.redrive);
its resultant, accelerations and points follow from them by the equation of motion, as every
row's do (history.Layout).

Measured against the event-located adaptive solution at rtol 1e-12 (tests/test_accuracy.py):
every column of the seed deck within 0.66-1.05 of its true error, of random scenes 0.5-1.6. The
companion costs one more time stepping and one pass of the elements. Where it does not apply (a
split step, exact kinematics, KR-alpha, spectra) or where its estimate comes near the warning,
the estimate is the adaptive solutions' (rbhyst.solve.estimate).
"""

from __future__ import annotations

import time

import numpy as np

from rbhyst.solve.kernels.layout import N_E, x_slice

#: the methods whose modified equation is written out here
METHODS = ("chang", "central-difference", "newmark")
#: the companion keeps every compute step's deformations: at most this many values
MAX_VALUES = 20_000_000


def unfit(plan) -> str | None:
    """Why a fixed-step plan's error cannot come from its companion (None: it can), before the run."""
    system, s = plan.system, plan.settings
    if s.integrator not in METHODS:
        return f"{s.integrator} has no modified equation here"
    if system.kinematics == "exact":
        return "exact kinematics"
    if s.spectra is not None:
        return "the spectra are estimated against the adaptive solution"
    if int(plan.substeps.max()) > 1 or max(plan.level0.values()) > 0:
        return "the excitation splits steps"
    if plan.cm.shape[0] > system.n:
        return "dampers that turn"
    if (plan.n_steps + 1) * max(plan.bvec.shape[0], system.n) > MAX_VALUES:
        return "too long a run to keep every step's deformation"
    return None


class Accelerations:
    """A run's tap (plan.run): at every compute step its coordinates, velocities and element
    forces, and the method's own acceleration A = M^-1 (p - R - C V) at the nodes, the load as
    the loop took it."""

    def __init__(self, plan):
        self.minv = plan.minv
        self.rb = np.ascontiguousarray(plan.system.bvec * plan.system.mult[:, None])
        self.c = plan.cm[:plan.system.n] if plan.damped else None
        x, st = plan._state()
        start = plan.start_row(x, st)
        self.a = [x[None, x_slice(plan.system.n, 2)].copy()]
        self.d, self.v, self.f = [start.d], [start.v], [start.f]
        self.wall_s = 0.0  # what tapping cost the run: the estimate's

    def __call__(self, load: np.ndarray, raw) -> None:
        tic = time.perf_counter()
        n = len(self.minv)
        force = load[1:, :n] - raw.f @ self.rb
        if self.c is not None:
            force -= raw.v @ self.c.T
        self.a.append(force * self.minv)
        self.d.append(raw.d.copy())
        self.v.append(raw.v.copy())
        self.f.append(raw.f.copy())
        self.wall_s += time.perf_counter() - tic


class Deformations:
    """The companion's tap: every compute step's coordinates, velocities and element deformations."""

    def __init__(self, start):
        self.d, self.v, self.u = [start.d], [start.v], [start.u]

    def __call__(self, load: np.ndarray, raw) -> None:
        self.d.append(raw.d.copy())
        self.v.append(raw.v.copy())
        self.u.append(raw.u.copy())


def source(method: str, a: np.ndarray, v: np.ndarray, mass: np.ndarray, c: np.ndarray | None,
           k0: np.ndarray, h: float) -> np.ndarray:
    """(nodes, n) -S: the load that takes the method's leading error out (module docstring)."""
    d2 = np.zeros_like(a)  # h^2 A''
    d2[1:-1] = a[2:] - 2.0 * a[1:-1] + a[:-2]
    d1 = None  # h A'
    if c is not None:
        d1 = np.zeros_like(a)
        d1[1:-1] = 0.5 * (a[2:] - a[:-2])
    if method == "newmark":
        out = -d2 * mass / 6.0
        if c is not None:
            out -= (h / 12.0) * d1 @ c.T
    elif method == "central-difference":
        out = d2 * mass / 12.0
        if c is not None:
            out += (h / 6.0) * d1 @ c.T
    else:  # chang
        out = d2 * mass / 12.0 + (0.25 * h * h) * a @ k0.T
        if c is not None:
            out += (5.0 * h / 12.0) * d1 @ c.T + (0.25 * h * h) * ((a @ c.T + v @ k0.T) / mass) @ c.T
    return out


def velocity_offset(method: str, a: np.ndarray, v: np.ndarray, mass: np.ndarray, c: np.ndarray | None,
                    k0: np.ndarray, h: float) -> np.ndarray:
    """(nodes, n) q' - V: how far the method's velocity is from the derivative of the smooth
    curve its nodes lie on (the same expansion as ``source``):

        newmark  h^2 A'/12,   central difference  -h^2 A'/6,
        chang    -h^2 [A'/6 + M^-1 (C A + K0 V)/4].

    The run starts at rest with V = 0, so its curve starts with q' = this: the companion starts
    with the opposite velocity, and its velocities are read as V + this."""
    d1 = np.empty_like(a)  # h A'
    d1[1:-1] = 0.5 * (a[2:] - a[:-2])
    d1[0] = -1.5 * a[0] + 2.0 * a[1] - 0.5 * a[2] if len(a) > 2 else 0.0
    d1[-1] = 1.5 * a[-1] - 2.0 * a[-2] + 0.5 * a[-3] if len(a) > 2 else 0.0
    if method == "newmark":
        return (h / 12.0) * d1
    if method == "central-difference":
        return -(h / 6.0) * d1
    out = -(h / 6.0) * d1 - (0.25 * h * h) * (v @ k0.T) / mass
    if c is not None:
        out -= (0.25 * h * h) * (a @ c.T) / mass
    return out


def companion_difference(plan, tap: Accelerations, compare_every: int):
    """(rows, k): the run's estimate columns (history.estimate_columns) less its companion's, at
    every compare_every-th step; and the companion's kernel seconds. None where an element's
    re-driven force left its range."""
    from rbhyst.solve.kernels.compiled import kernel

    system, s = plan.system, plan.settings
    a, v = np.concatenate(tap.a), np.concatenate(tap.v)
    extra = source(s.integrator, a, v, system.mass, tap.c, system.K0, s.dt)
    offset = velocity_offset(s.integrator, a, v, system.mass, tap.c, system.K0, s.dt)
    x, st = plan._state()
    x[x_slice(system.n, 1)] = -offset[0]
    st0 = st[0].copy()  # (the loop steps st in place)
    keep = Deformations(plan.start_row(x, st))
    wall = 0.0
    for _, _, _, load, raw, took in plan.chunks(x, st, extra=extra):
        wall += took
        keep(load, raw)
    u = np.ascontiguousarray(np.concatenate(keep.u))
    f = np.empty_like(u)
    if kernel("redrive")(plan.params, st0, u, f) >= 0:
        return None, wall
    rows = slice(0, len(u), compare_every)
    dd = np.concatenate(tap.d)[rows] - np.concatenate(keep.d)[rows]
    dv = v[rows] - np.concatenate(keep.v)[rows] - offset[rows]
    df = np.concatenate(tap.f)[rows] - f[rows]
    return plan.layout.difference(dd, dv, df), wall
