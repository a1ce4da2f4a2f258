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
its deformation turned, not at the turn (seed eq. 14), O(h^2) off; the force carries that along
the branch, and the motion the drift it leaves (a body that creeps under cyclic load). The
companion therefore steps with every turn put within its step (kernels.layout.LOCATED: the
vertex of the parabola through the element's last three deformations), and its rows report
the forces with each turn where it falls: a row whose element turned before it (found by the
next step) takes its force on the new branch (kernels.loop, LOCATED), or where the run split a
step into substeps the forces are re-driven between the rows by the same rule
(rbhyst.solve.kernels.redrive); its resultant,
accelerations and points follow from them by the equation of motion, as every row's do
(history.Layout).

Measured against the event-located adaptive solution at rtol 1e-12 (tests/test_accuracy.py,
tests/test_companion.py): every column of the seed deck within 0.93-1.12 of its true error; of 24
random scenes with the three methods (71 of 72 runs) 97.9 % of 1,173 columns within [0.5, 2]
(0.47-4.2, the widest on short pulses and on stiffening elements). The companion costs one more
time stepping (and one pass of the elements where the run split a step). Steps the run's stiffness monitor split into substeps are split alike in the companion, its
source taken at the substeps' h (kernels.loop: ``levels``; its own monitor does not judge again:
its states are the run's within the run's error, and a step split otherwise would carry another
error than the one its source takes out). Where it does not apply (exact kinematics, KR-alpha,
spectra, a step whose Newton iterations fail in the companion where the run's converged) or
where its estimate exceeds 20 %, the estimate is the adaptive solutions' (rbhyst.solve.estimate).

The classes here keep the run's rows at every compute node (RunTap), which a short run's
estimate does in one compiled call; a run whose arrays would pass WHOLE_RUN_BYTES steps its
companion alongside it instead, a chunk at a time (rbhyst.solve.alongside: the same numbers).
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from rbhyst.solve.kernels.layout import (ESTIMATE_DONE, ESTIMATE_FAILED, ESTIMATE_PROBED, ESTIMATE_TOO_LARGE, LOCATED,
                                         MODIFIED, SMALL, x_slice)

#: the methods whose modified equation is written out here
METHODS = tuple(MODIFIED)
#: a run whose tap and companion would keep more than this many bytes of its compute nodes (the
#: estimate's arrays of the whole run: whole_run_bytes) steps its companion alongside it instead, a
#: chunk at a time (rbhyst.solve.alongside: the same numbers in a chunk's memory); below, the whole
#: run's arrays let the companion and its check be one compiled call (about 80,000 nodes of the
#: seed deck)
WHOLE_RUN_BYTES = 32_000_000


def unfit(plan) -> str | None:
    """Why a fixed-step plan's error cannot come from its companion (None: it can), before the run."""
    system, s = plan.system, plan.settings
    if s.integrator not in METHODS:
        return f"{s.integrator} has no modified equation here"
    if system.rotation_index != SMALL:
        # (the loop locates the companion's turns with the seed's rows only: with exact ones it
        # would share the run's drift, as the machine on its mounts shows: u2 at 0.1 of its error)
        return "exact kinematics"
    if s.spectra is not None:
        return "the spectra are estimated against the adaptive solution"
    if plan.cm.shape[0] > system.n:
        return "dampers that turn"
    return None


def whole_run_bytes(plan) -> int:
    """About what the tap and the companion of a whole run keep (RunTap, estimate_in_one_call's
    arrays): at every compute node its time and level, the run's d, v, f and load, the source,
    the offset and the accelerations, the companion's rows and load."""
    n, ne = plan.system.n, plan.bvec.shape[0]
    per_node = 8 + 7 * n + 4 * ne + 2 * n  # (the load as wide as the coordinates)
    return 8 * per_node * (plan.compute_steps + 1)


class RunTap:
    """A run's tap (plan.run): at every compute step its time, coordinates, velocities and element
    forces, and the load as the loop took it, in arrays of the whole run (its compute nodes are
    known before it runs: the stiffness monitor splits a step within it, not into more rows).
    The loop writes the rows straight into them (``buffers``): no copy."""

    def __init__(self, plan):
        self.c = plan.cm[:plan.system.n] if plan.damped else None
        n = plan.system.n
        nodes = plan.compute_steps + 1
        x, st = plan.initial_state()
        start = plan.start_row(x, st)
        self._rows = KeptRows(start, nodes)  # d, v, f at every node; u and e a chunk's at a time
        self.a0 = x[x_slice(n, 2)].copy()  # (the loop's own acceleration at t = 0: at rest under the load)
        self.d, self.v, self.f = self._rows.d, self._rows.v, self._rows.f
        self.t = np.empty(nodes)  # every compute node's time, as the loop took it
        self.t[0] = 0.0
        self.load = None  # the scene's load at every compute node (the companion's, less its source)
        self.levels = np.empty(nodes - 1, dtype=np.int64)  # every compute step's substep level (the monitor's)
        self.next = 1  # the next node to fill
        self.wall_s = 0.0  # what tapping cost the run: the estimate's

    def buffers(self, node: int, rows: int):
        return self._rows.buffers(node, rows)

    def __call__(self, load: np.ndarray, raw, levels: np.ndarray) -> None:
        tic = time.perf_counter()
        k, m = self.next, len(raw.t)
        assert np.may_share_memory(raw.d, self.d[k:k + m]), "the rows are written into the tap's arrays"
        if self.load is None:
            self.load = np.empty((len(self.t), load.shape[1]))
            self.load[0] = load[0]
        self.load[k:k + m] = load[1:]  # (chunks share their first node)
        self.t[k:k + m] = raw.t
        self.levels[k - 1:k - 1 + m] = levels
        self.next = k + m
        self.wall_s += time.perf_counter() - tic


class KeptRows:
    """Rows of every compute node from the start row on, which the loop writes into: those of
    ``keep`` (d, v, u, f) in arrays of them all, the others a chunk's at a time (plan.chunks'
    ``into``, ``buffers``; plan.step_through's ``arrays``)."""

    def __init__(self, start, nodes: int, keep=("d", "v", "f")):
        self._widths = {k: getattr(start, k).shape[1] for k in ("d", "v", "u", "f", "e")}
        self._keep = keep
        for k in keep:
            whole = np.empty((nodes, self._widths[k]))
            whole[0] = getattr(start, k)[0]
            setattr(self, k, whole)
        self._spare = {}

    def buffers(self, node: int, rows: int):
        """The arrays the loop writes a chunk's rows into, from compute node ``node`` + 1 on, and
        ``fb``, the row of forces before them (the loop patches a turn the chunk's first step
        put before it: kernels.loop's out_fb)."""
        out = {}
        for k, width in self._widths.items():
            if k in self._keep:
                out[k] = getattr(self, k)[node + 1:node + 1 + rows]
            else:
                spare = self._spare.get(k)
                if spare is None or len(spare) < rows:
                    spare = self._spare[k] = np.empty((rows, width))
                out[k] = spare[:rows]
        out["fb"] = self.f[node] if "f" in self._keep else np.empty(self._widths["f"])
        return SimpleNamespace(**out)

    def arrays(self, scratch: int):
        """plan.step_through's arrays (kernels.through): d, v, u, f (those kept of every node,
        the others ``scratch`` rows), e and fb (scratch), which are whole, and no nodes to pick."""
        out = [getattr(self, k) if k in self._keep else np.empty((scratch, self._widths[k])) for k in "dvuf"]
        whole = np.array([k in self._keep for k in "dvuf"])
        none = np.empty((1, 0))
        return (*out, np.empty((scratch, self._widths["e"])), np.empty(self._widths["f"]), whole,
                np.empty(0, dtype=np.int64), none, none, none)


class PickedRows(KeptRows):
    """d, v and f at the compute nodes ``take`` only (a slice of them, or their indices in
    order; node 0 the start row), picked from each segment's rows as the loop writes them: the
    probe's (Companion.probe), which needs no more of a long run."""

    def __init__(self, start, take, count: int):
        super().__init__(start, 0, keep=())
        self.take = take
        self.d, self.v, self.f = (np.empty((count, w)) for w in (start.d.shape[1], start.v.shape[1], start.f.shape[1]))
        self.d[0], self.v[0], self.f[0] = start.d[0], start.v[0], start.f[0]

    def arrays(self, scratch: int):
        take = self.take
        nodes = np.arange(take.start, take.stop, take.step) if isinstance(take, slice) else np.asarray(take)
        out = super().arrays(scratch)
        return (*out[:7], np.ascontiguousarray(nodes[1:], dtype=np.int64), self.d, self.v, self.f)


class Companion:
    """The run's companion, ready to step: its load (-S at every compute node, none within a step of
    a signal's corner) and starting velocity worked out once from the run's tap."""

    def __init__(self, plan, tap: RunTap, compare_every: int):
        self.plan = plan
        assert tap.next == len(tap.t), "the run's tap missed compute steps"
        # the steps the run's stiffness monitor split are the companion's too (its source is the
        # method's error at the substeps' h)
        self.levels = tap.levels
        self.extra, self.offset = source_from_run(plan, tap)
        # the run at the compared steps, its velocities read on its curve
        self.take = plan.compared_nodes(compare_every)
        self.d, self.v_run = tap.d[self.take], tap.v[self.take]
        self.v = self.v_run - self.offset[self.take]
        self.f = tap.f[self.take]
        self.load = tap.load

    def run(self):
        """(dd, dv, df): the run's coordinates, velocities and element forces less the companion's
        at the compared steps (history.Layout.largest_change makes every column's of them), and
        the companion's kernel seconds; None where Newton's iterations split a step further than
        the run's or a re-driven force left its element's range. The companion's forces are
        those of its elements driven with every turn put where it falls, before or after the
        node: its rows' (kernels.loop, LOCATED), or re-driven between them where the run split
        a step (``redriven``)."""
        plan = self.plan
        n = plan.system.n
        x, st = plan.initial_state()
        x[x_slice(n, 1)] = -self.offset[0]
        st0 = st[0].copy()  # (the loop steps st in place)
        split = bool(self.levels.any())  # (then the forces are re-driven between the rows)
        keep = KeptRows(plan.start_row(x, st), len(self.extra), keep=("d", "v", "u" if split else "f"))
        load = self.load.copy()
        load[:, :n] += self.extra
        # every turn put where it falls within its step (LOCATED): the companion's motion then
        # carries none of the run's O(h^2) branch origins, whose drift (a body that creeps under
        # cyclic load) it would otherwise share and cancel
        wall, levels = plan.step_through(x, st, load, self.levels, keep, rot=LOCATED)
        if not np.array_equal(levels, self.levels):
            return None, wall
        f = keep.f if not split else redriven(plan.params, st0, keep.u)
        if f is None:
            return None, wall
        rows = self.take
        if isinstance(rows, slice):  # (views of the companion's rows: the differences in place)
            d, v, f = keep.d[rows], keep.v[rows], f[rows]
            return (np.subtract(self.d, d, out=d), np.subtract(self.v, v, out=v), np.subtract(self.f, f, out=f)), wall
        return (self.d - keep.d[rows], self.v - keep.v[rows], self.f - f[rows]), wall

    def probe(self, eps: float):
        """(dd, dv, df): how far the run moves (its coordinates, velocities and element forces at
        the compared steps) when eps times the companion's source and starting velocity are added
        to it, and the kernel seconds: the same stepping as the run's, its turns at the nodes. A
        determined history moves by about eps times its error, a sensitive one by as much as the
        error itself. None where Newton's iterations split a step further than the run's."""
        plan = self.plan
        n = plan.system.n
        x, st = plan.initial_state()
        x[x_slice(n, 1)] = -eps * self.offset[0]
        start = plan.start_row(x, st)
        if isinstance(self.take, slice) and self.take.step == 1:  # every node compared: kept as written
            rows = KeptRows(start, len(self.d))
        else:
            rows = PickedRows(start, self.take, len(self.d))
        load = self.load.copy()
        load[:, :n] += eps * self.extra
        wall, levels = plan.step_through(x, st, load, self.levels, rows)
        if not np.array_equal(levels, self.levels):
            return None, wall
        d, v, f = rows.d, rows.v, rows.f
        return (np.subtract(self.d, d, out=d), np.subtract(self.v_run, v, out=v), np.subtract(self.f, f, out=f)), wall


def redriven(params: np.ndarray, st0: np.ndarray, u: np.ndarray) -> np.ndarray | None:
    """(samples, ne) every element's force driven from its state st0 along its deformations u
    (samples, ne), each reversal located within its step (kernels.redrive), or None where one
    left its range."""
    from rbhyst.solve.kernels.compiled import kernel

    f = np.empty_like(u)
    return None if kernel("redrive")(params, st0, u, f) >= 0 else f


def source_and_offset(method: str, a: np.ndarray, v: np.ndarray, t: np.ndarray, h: np.ndarray,
                      mass: np.ndarray, c: np.ndarray | None, k0: np.ndarray, near: np.ndarray):
    """(-S, q' - V), each (nodes, n): the load that takes the method's leading error out (the
    module docstring's S), none at the nodes ``near``, and how far the method's velocity is from
    the derivative of the smooth curve its nodes lie on (the same expansion), from its
    accelerations a and velocities v at the nodes t, h the step the loop takes after each
    (rbhyst.solve.kernels.modified writes both out, one compiled pass). The run starts at rest
    with V = 0, so its curve starts with q' = the offset: the companion starts with the opposite
    velocity, and its velocities are read as V + the offset."""
    from rbhyst.solve.kernels.compiled import kernel

    n = a.shape[1]
    extra, offset = np.empty_like(a), np.empty_like(a)
    damped = c is not None
    kernel("modified")(MODIFIED[method], np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(v, dtype=float),
                       np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(h, dtype=float),
                       np.ascontiguousarray(mass, dtype=float),
                       np.ascontiguousarray(c, dtype=float) if damped else np.zeros((n, n)), damped,
                       np.ascontiguousarray(k0, dtype=float), np.ascontiguousarray(near, dtype=bool), extra, offset,
                       np.empty(n), np.empty(n), np.empty(n))
    return extra, offset


def signal_corners(system) -> list[float]:
    """The times of every analytic signal's start, end and corners, and where a record jumps (its
    start or end off zero): no source within 1.5 h of one."""
    from rbhyst.model.records import Series
    from rbhyst.model.system import record_jumps

    return [b for sig in system.excitation.signals.values()
            for b in (record_jumps(sig) if isinstance(sig, Series) else sig.breakpoints)]


def source_from_run(plan, tap: RunTap):
    """(-S, q' - V) of source_and_offset from the rows and load the run's tap kept, in one compiled
    pass (kernels.modified.companion_source): the method's accelerations M^-1 (p - R - C V) at
    the nodes (the seed's small rotations: R = sum mult b f), each step's h at the level the
    run took it, no source within 1.5 h of an analytic signal's start, end or corner."""
    from rbhyst.solve.kernels.compiled import kernel

    system, s = plan.system, plan.settings
    assert system.rotation_index == SMALL, "the companion's rows are the seed's"
    nodes, n = len(tap.t), system.n
    breaks = signal_corners(system)
    extra, offset, a = np.empty((3, nodes, n))
    damped = tap.c is not None
    kernel("companion_source")(MODIFIED[s.integrator], tap.load, tap.v, tap.f, tap.a0, plan.rb,
                               tap.c if damped else np.zeros((n, n)), damped, plan.minv,
                               np.ascontiguousarray(system.mass, dtype=float), plan.K0, tap.t, tap.levels, plan.bounds,
                               plan.substeps, s.dt, np.array(breaks, dtype=float), a, np.empty(nodes),
                               np.empty(nodes, dtype=bool), extra, offset, *np.empty((3, n)))
    return extra, offset


def estimate_in_one_call(plan, tap: RunTap, compare_every: int, layout, scales: np.ndarray, check: float,
                         largest: float, eps: float):
    """What rbhyst.solve.estimate takes from the companion where its check does not run on a core
    of its own: the companion's every column's largest change (history.Layout.largest_change of
    Companion.run's differences) and, where it lies between ``check`` and ``largest`` of
    ``scales`` (estimate.scaled_errors), the probe's at ``eps`` (Companion.probe's), in one
    compiled call (kernels.estimate): (changed, moved, seconds); changed None where the
    adaptive solutions must say it, moved None where the probe was not needed (or the estimate
    is past ``largest``: then not computed)."""
    from rbhyst.solve.kernels.compiled import kernel
    from rbhyst.solve.kernels.layout import INFO_SIZE, N_E, N_STATE, N_W
    from rbhyst.solve.plan import raise_on_failure

    system, s = plan.system, plan.settings
    assert system.rotation_index == SMALL, "the companion's rows are the seed's"
    assert tap.next == len(tap.t), "the run's tap missed compute steps"
    nodes, n = len(tap.t), system.n
    ne = plan.bvec.shape[0]
    count = plan.compute_steps // compare_every + 1  # (the compared nodes: plan.compared_nodes', in the call)
    segments, coefs, _ = plan._through
    breaks = signal_corners(system)
    x0, st0 = plan.initial_state()
    arms, ct, back = layout._change_terms
    width = 3 * n + 2 * arms.shape[1] * arms.shape[0] + ne  # (Layout.largest_change's columns, kernel rows')
    top_c, top_p = np.empty(width), np.empty(width)
    info = np.zeros(INFO_SIZE)
    n_q = plan.bvec.shape[1]
    damped = tap.c is not None
    tic = time.perf_counter()
    code = kernel("companion_estimate", n_q)(
        plan.method.kernel_id, coefs, plan._mass,
        plan._minv, plan.cm, plan.damped, plan.bvec, plan.axial, system.rotation_index, system.mult, plan.params,
        plan.wgt, segments, s.dt, s.max_omega_dt, s.max_substep_level, s.newton_tol, s.newton_max_iter,
        MODIFIED[s.integrator], tap.load, tap.t, tap.levels, tap.d, tap.v, tap.f, tap.a0, x0, st0, plan.rb,
        tap.c if damped else np.zeros((n, n)), plan.minv, np.ascontiguousarray(system.mass, dtype=float), plan.K0,
        plan.bounds, plan.substeps, np.array(breaks, dtype=float), compare_every, np.empty(count, dtype=np.int64), ct, layout.damped, back,
        layout._back is not None, arms, layout._minv, layout._expand, scales, check, largest, eps,
        np.empty((nodes, n)), np.empty((nodes, n)), np.empty((nodes, n)), np.empty(nodes), np.empty(nodes, dtype=bool),
        np.empty_like(tap.load), np.empty_like(x0), np.empty_like(st0), np.zeros((ne, N_STATE)), np.zeros((ne, 2)),
        np.zeros((ne, n_q)), np.zeros((N_W, n_q)), np.zeros((n_q, n_q)), np.empty((nodes, n)), np.empty((nodes, n)),
        np.empty((nodes, ne)), np.empty((nodes, ne)), np.empty((nodes, N_E)), np.empty(ne), np.empty((nodes, ne)),
        np.zeros(4, dtype=bool), np.empty((count, n)), np.empty((count, n)), np.empty((count, ne)), np.empty(count - 1, dtype=np.int64),
        np.empty((count, n)), np.empty((count, n)), np.empty((count, ne)), top_c, top_p, np.empty((4, n)),
        np.empty((3, n)), np.empty(nodes - 1, dtype=np.int64), True, info)
    wall = time.perf_counter() - tic
    if code == ESTIMATE_FAILED:
        raise_on_failure(system, s, info)
        raise AssertionError("the companion's loop took fewer steps than asked, or the compared nodes are not the run's")
    if code not in (ESTIMATE_DONE, ESTIMATE_PROBED, ESTIMATE_TOO_LARGE):
        return None, None, wall
    expand = layout.expand_change
    return expand(top_c), (expand(top_p) if code == ESTIMATE_PROBED else None), wall
