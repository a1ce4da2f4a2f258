"""The error estimate's companion stepped alongside its run, a chunk behind it: an estimate whose
memory is a chunk's, whatever the run's length.

rbhyst.solve.companion keeps the run's rows at every compute node and makes the companion's
load from them after the run: some 400 bytes a node, 800 MB for 2 million. Here the run's tap
(plan.run's ``tap``) takes each chunk as the loop writes it:

- the companion's source -S and the offset at a node need only the run's accelerations at the
  node and its two neighbours and the step after it (kernels.modified.window_source over the
  chunk's nodes and the one before them): a chunk's last node waits for the next chunk;
- the companion steps on to the last node with its source (the loop carries its state between
  calls), in pieces of equal splitting;
- a row of the companion's is compared once it is final: the next step may patch its force (a
  turn found before it: kernels.loop, LOCATED), and its force re-driven between the rows
  (kernels.redrive.redrive_on) needs the deformation after it. Which of the two forces counts
  depends on whether the run split any step, known at its end: both are compared;
- what is compared is reduced at once (history.Layout.largest_change: each column's largest),
  at the nodes the whole companion compares (plan.compared_nodes).

Where a core is free, the companion works on a thread of its own a chunk behind the loop
(Behind): the seed deck's 2 million steps streamed took 19.4 s with the whole run's companion
and take 12.9 s so (the CSV's threads beside them).

The probe (the check near the warning) needs the same source, so it steps where the estimate
asks for it, after the run: the run stepped once more, a chunk at a time (the same rows to the
bit), with the probe beside it. The numbers are Companion.run's and Companion.probe's, bit for
bit (tests/test_alongside.py).
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from rbhyst.solve.companion import KeptRows, signal_corners
from rbhyst.solve.kernels.layout import INFO_SIZE, I_STATUS, LOCATED, MODIFIED, N_E, OK, x_slice


class Nodes:
    """The run's compute nodes a chunk at a time, and the companion's source (-S) and offset at
    those whose neighbours and step are known (nodes 0 .. ready - 1): rows of nodes base ..
    base + count - 1, the last one or two of a chunk carried into the next."""

    def __init__(self, plan, rows: int):
        system = plan.system
        n, ne = system.n, plan.bvec.shape[0]
        self.plan, self.n = plan, n
        self.total = plan.compute_steps + 1
        cap = rows + 3
        self.t, self.h = np.empty(cap), np.empty(cap)
        self.levels = np.empty(cap, dtype=np.int64)  # the level of the step after each node
        self.d, self.v, self.a, self.extra, self.offset = (np.empty((cap, n)) for _ in range(5))
        self.f = np.empty((cap, ne))
        self.load = None  # (as wide as the loop's load: known with the first chunk)
        self._extra_w, self._offset_w = np.empty((cap, n)), np.empty((cap, n))
        self._near = np.empty(cap, dtype=bool)
        x, st = plan.initial_state()
        start = plan.start_row(x, st)
        self.t[0], self.d[0], self.v[0], self.f[0] = 0.0, start.d[0], start.v[0], start.f[0]
        self.a[0] = x[x_slice(n, 2)]  # (the loop's own acceleration at t = 0)
        self.base, self.count, self.ready = 0, 1, 0
        self.split = False  # whether the run split any step into substeps
        self._c = np.ascontiguousarray(plan.cm[:n]) if plan.damped else np.zeros((n, n))
        self._mass = np.ascontiguousarray(system.mass, dtype=float)
        self._breaks = np.array(signal_corners(system), dtype=float)
        self._segment_nodes = np.concatenate([[0], np.cumsum(np.diff(plan.bounds) * plan.substeps)])
        self._work = np.empty((3, n))

    def row(self, node: int) -> int:
        return node - self.base

    def segment(self, step: int) -> int:
        """The run of equal splitting (plan.bounds, plan.substeps) compute step ``step`` is in."""
        return int(np.searchsorted(self._segment_nodes, step, side="right")) - 1

    @property
    def final(self) -> bool:
        return self.base + self.count == self.total

    def add(self, load: np.ndarray, raw, levels: np.ndarray) -> None:
        """A chunk of the run (plan.run's tap): its load at its compute nodes (the first the last
        node held), its rows and each step's substep level; then the source of every node it
        makes known (``ready``)."""
        r, m = self.count, len(raw.t)
        if self.load is None:
            self.load = np.empty((len(self.t), load.shape[1]))
            self.load[0] = load[0]
        rows = slice(r, r + m)
        self.t[rows], self.d[rows], self.v[rows], self.f[rows] = raw.t, raw.d, raw.v, raw.f
        self.load[rows] = load[1:]
        self.levels[r - 1:r - 1 + m] = levels
        self.split = self.split or bool(levels.any())
        nsub = int(self.plan.substeps[self.segment(self.base + r - 1)])  # (a chunk splits alike throughout)
        self.h[r - 1:r - 1 + m] = np.ldexp(self.plan.settings.dt / nsub, -levels)  # (exact: powers of two)
        self.count += m
        if self.final:
            self.h[self.count - 1] = self.h[self.count - 2]  # (companion_source's last node)
        self._source()

    def _source(self) -> None:
        from rbhyst.solve.kernels.compiled import kernel

        lo = self.row(max(self.ready - 1, 0))  # the window starts where the acceleration is known
        hi = self.count
        if hi - lo < 3 and not self.final:  # (a window of two nodes would take the run's ends' differences)
            return
        plan = self.plan
        kernel("window_source")(MODIFIED[plan.settings.integrator], self.load[lo:hi], self.v[lo:hi], self.f[lo:hi],
                                self.a[lo].copy(), plan.rb, self._c, plan.damped, plan.minv, self._mass, plan.K0,
                                self.t[lo:hi], self.h[lo:hi], self._breaks, self.a[lo:hi], self._near[lo:hi],
                                self._extra_w[:hi - lo], self._offset_w[:hi - lo], *self._work)
        ready = self.total if self.final else self.base + hi - 1
        first = self.row(self.ready)  # (the window's first node kept the source of the window before)
        self.extra[first:self.row(ready)] = self._extra_w[first - lo:self.row(ready) - lo]
        self.offset[first:self.row(ready)] = self._offset_w[first - lo:self.row(ready) - lo]
        self.ready = ready

    def drop_before(self, node: int) -> None:
        """Forget the nodes before ``node`` (every follower has stepped past them)."""
        k = self.row(node)
        if k <= 0:
            return
        keep = self.count - k
        for arr in (self.t, self.h, self.levels, self.d, self.v, self.a, self.f, self.load, self.extra, self.offset):
            arr[:keep] = arr[k:k + keep]
        self.base, self.count = node, keep


class Follower:
    """The companion (``located``: every turn put within its step, its forces compared as its rows
    give them and re-driven) or the probe, stepped on as the nodes' source becomes known, its
    rows compared with the run's at the compared nodes once final: every column's largest change
    (history.Layout.largest_change)."""

    def __init__(self, plan, eps: float, located: bool, compare_every: int, rows: int):
        n, ne = plan.system.n, plan.bvec.shape[0]
        self.plan, self.eps, self.located, self.every = plan, eps, located, compare_every
        self.last_compared = (plan.compute_steps // compare_every) * compare_every
        cap = rows + 4
        self.x, self.st = plan.initial_state()
        start = plan.start_row(self.x, self.st)
        self._state = self.st[0].copy()  # the re-drive's element states (the loop steps st in place)
        # rows of nodes lo .., the node stepped to held (its force may yet be patched) and the one
        # before it (the re-drive's start)
        self.d, self.v = np.empty((cap, n)), np.empty((cap, n))
        self.u, self.f, self.f_re = np.empty((cap, ne)), np.empty((cap, ne)), np.empty((cap, ne))
        self.d[0], self.v[0], self.u[0], self.f[0] = start.d[0], start.v[0], start.u[0], start.f[0]
        self.f_re[0] = start.f[0]
        self._e = np.empty((cap, N_E))
        self._load = None
        self.lo = self.node = 0
        self.top = self.top_re = None  # the largest changes, the forces as the rows give them / re-driven
        self.split = False  # Newton's iterations split a step further than the run's
        self.failed = None  # the loop's info where it failed
        self.out_of_range = False  # a re-driven force left its element's range
        self.wall = 0.0  # the seconds of its source, stepping, re-drive and comparison

    @property
    def alive(self) -> bool:
        return not self.split and self.failed is None

    def step(self, nodes: Nodes) -> None:
        """Step to the last node whose source is known, compare the rows that are final."""
        c, r = self.node, nodes.ready - 1
        if r <= c or not self.alive:
            return
        plan, n = self.plan, self.plan.system.n
        if self._load is None:
            self._load = np.empty((len(self.d), nodes.load.shape[1]))
        i0 = nodes.row(c)
        load = self._load[:r - c + 1]
        load[:] = nodes.load[i0:i0 + r - c + 1]
        load[:, :n] += self.eps * nodes.extra[i0:i0 + r - c + 1]
        if c == 0:  # the run starts at rest: its curve with q' = the offset, the follower opposite
            self.x[x_slice(n, 1)] = -self.eps * nodes.offset[i0]
        p = c
        while p < r and self.alive:
            seg = nodes.segment(p)
            q = min(r, int(nodes._segment_nodes[seg + 1]))
            self._piece(nodes, p, q, c, int(plan.substeps[seg]))
            p = q
        if not self.alive:
            return
        self.node = r
        final = nodes.final and r == nodes.total - 1
        self._compare(nodes, c, r if final else r - 1, final)
        keep = self.row(r - 1)  # (the held node and the one before it, for the next call)
        for arr in (self.d, self.v, self.u, self.f, self.f_re):
            arr[:2] = arr[keep:keep + 2]
        self.lo = r - 1

    def row(self, node: int) -> int:
        return node - self.lo

    def _piece(self, nodes: Nodes, p: int, q: int, c: int, nsub: int) -> None:
        """Steps p .. q - 1 (one splitting) at the run's levels, the rows of nodes p + 1 .. q."""
        plan = self.plan
        a, b = self.row(p), self.row(q)
        buf = SimpleNamespace(d=self.d[a + 1:b + 1], v=self.v[a + 1:b + 1], u=self.u[a + 1:b + 1],
                              f=self.f[a + 1:b + 1], e=self._e[:q - p], fb=self.f[a])
        levels = nodes.levels[nodes.row(p):nodes.row(q)]
        taken = levels.copy()
        info = np.zeros(INFO_SIZE)
        h_c = plan.settings.dt / nsub
        done = plan._call(self._load[p - c:q - c + 1], float(nodes.t[nodes.row(p)]), nsub, h_c, 1, q - p, self.x,
                          self.st, buf, rot=LOCATED if self.located else None, levels=taken, force=True, info=info)
        if int(info[I_STATUS]) != OK or done != q - p:
            self.failed = info
        elif not np.array_equal(taken, levels):
            self.split = True

    def _compare(self, nodes: Nodes, c: int, last: int, final: bool) -> None:
        """Every column's largest change at the compared nodes c .. last (the re-drive first)."""
        from rbhyst.solve.kernels.compiled import kernel

        if self.located and not self.out_of_range:
            # the forces with every turn where it falls, between the rows (companion.redriven):
            # from the node before c (at node 0 the start state) through the held node
            start = max(c - 1, 0)
            u = self.u[self.row(start):self.row(self.node) + 1]
            f = self.f_re[self.row(start):self.row(self.node) + 1]
            if kernel("redrive_on")(self.plan.params, self._state, u, f, final) >= 0:
                self.out_of_range = True
        first = -(-c // self.every) * self.every
        end = min(last, self.last_compared) + 1
        if end <= first:
            return
        # (slices, not index arrays: views of the rows, no copies gathered)
        assert first >= max(self.lo, nodes.base), "a compared node before the rows held"
        mine = slice(first - self.lo, end - self.lo, self.every)
        theirs = slice(first - nodes.base, end - nodes.base, self.every)
        dd = nodes.d[theirs] - self.d[mine]
        v_run = nodes.v[theirs] - nodes.offset[theirs] if self.located else nodes.v[theirs]
        dv = v_run - self.v[mine]
        layout = self.plan.layout
        self.top = _larger(self.top, layout.largest_change(dd, dv, nodes.f[theirs] - self.f[mine]))
        if self.located and not self.out_of_range:
            self.top_re = _larger(self.top_re, layout.largest_change(dd, dv, nodes.f[theirs] - self.f_re[mine]))

    @property
    def nbytes(self) -> int:
        arrays = (self.d, self.v, self.u, self.f, self.f_re, self._e, self._state, self._load)
        return sum(a.nbytes for a in arrays if a is not None)


def _larger(top, new):
    return new if top is None else np.maximum(top, new)


class Behind:
    """A follower fed the chunks of a stepping (plan.chunks' ``into``: ``buffers`` gives the
    arrays the loop writes a chunk into), on a thread of its own one chunk behind the loop where
    ``beside`` (two sets of arrays in turn: the loop writes one while the follower reads the
    other; the kernels let go of Python's lock), else in the loop's thread."""

    def __init__(self, plan, nodes: Nodes, follower: Follower, beside: bool):
        x, st = plan.initial_state()
        start = plan.start_row(x, st)
        self.nodes, self.follower = nodes, follower
        self._spares = [KeptRows(start, 0, keep=()) for _ in range(2 if beside else 1)]
        self._turn = 0
        self._beside = beside
        self._ahead = None  # the follower's work on the last chunk, where beside

    def buffers(self, node: int, rows: int):
        return self._spares[self._turn % len(self._spares)].buffers(node, rows)

    def feed(self, load: np.ndarray, raw, levels: np.ndarray) -> None:
        from rbhyst.solve.beside import Beside

        self.wait()
        if self._beside:
            self._ahead = Beside(_follow, self.nodes, self.follower, load, raw, levels, name="rbhyst companion")
        else:
            _follow(self.nodes, self.follower, load, raw, levels)
        self._turn += 1

    def wait(self) -> None:
        """Until the follower has taken every chunk fed (and raise what it raised)."""
        ahead, self._ahead = self._ahead, None
        if ahead is not None:
            ahead.result()

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for spare in self._spares for a in spare._spare.values())


class Alongside:
    """A run's tap (plan.run's ``tap``) that steps its companion alongside it: the estimate of
    rbhyst.solve.companion in a chunk's memory (the module docstring). ``changed()`` after the
    run, ``probe(eps)`` where the estimate asks for it. ``beside``: a core is free for the
    companion, which then steps on a thread of its own a chunk behind the run."""

    streamed = True

    def __init__(self, plan, compare_every: int, beside: bool = False):
        self.plan, self.compare_every, self.beside = plan, compare_every, beside
        self.rows = max(plan.fine_chunk, plan.nsub)  # (the most compute steps a chunk of the loop's holds)
        self.nodes = Nodes(plan, self.rows)
        self.companion = Follower(plan, 1.0, True, compare_every, self.rows)
        self._behind = Behind(plan, self.nodes, self.companion, beside)
        self.wall_s = 0.0  # what the tap cost the run

    def buffers(self, node: int, rows: int):
        return self._behind.buffers(node, rows)

    def __call__(self, load: np.ndarray, raw, levels: np.ndarray) -> None:
        tic = time.perf_counter()
        self._behind.feed(load, raw, levels)
        self.wall_s += time.perf_counter() - tic

    def changed(self):
        """(every column's largest change between the run and its companion, as
        Layout.largest_change gives them, or None where Newton's iterations split a step further
        than the run's or a re-driven force left its element's range; the companion's kernel
        seconds). Raises where the companion's loop failed, as plan.step_through does."""
        tic = time.perf_counter()
        self._behind.wait()
        self.wall_s += time.perf_counter() - tic
        c = self.companion
        assert self.nodes.final and c.node == self.nodes.total - 1, "the run's tap missed compute steps"
        _raise_on(self.plan, c)
        if c.split or (self.nodes.split and c.out_of_range):
            return None, c.wall
        return (c.top_re if self.nodes.split else c.top), c.wall

    def probe(self, eps: float):
        """(every column's largest change of the run under eps of the companion's source, or None
        where Newton's iterations split a step further than the run's; kernel seconds): the run
        stepped again a chunk at a time (its rows to the bit) with the probe beside it."""
        plan = self.plan
        probe = Follower(plan, eps, False, self.compare_every, self.rows)
        behind = Behind(plan, Nodes(plan, self.rows), probe, self.beside)
        x, st = plan.initial_state()
        wall = 0.0
        for _, _, _, load, raw, levels, took in plan.chunks(x, st, fine=True, into=behind):
            wall += took
            behind.feed(load, raw, levels)
        behind.wait()
        _raise_on(plan, probe)
        return (None if probe.split else probe.top), wall + probe.wall

    @property
    def nbytes(self) -> int:
        """The bytes of the arrays the tap keeps (a chunk's: not the run's)."""
        n = self.nodes
        arrays = [n.t, n.h, n.levels, n.d, n.v, n.a, n.extra, n.offset, n.f, n.load, n._extra_w, n._offset_w, n._near]
        return sum(a.nbytes for a in arrays if a is not None) + self.companion.nbytes + self._behind.nbytes


def _follow(nodes: Nodes, follower: Follower, load, raw, levels) -> None:
    """A chunk of the run into the nodes, the follower on through them (its seconds counted)."""
    tic = time.perf_counter()
    nodes.add(load, raw, levels)
    follower.step(nodes)
    nodes.drop_before(max(nodes.ready - 1, 0))  # (the next window's first node, where the follower is)
    follower.wall += time.perf_counter() - tic


def _raise_on(plan, follower: Follower) -> None:
    if follower.failed is not None:
        from rbhyst.solve.plan import raise_on_failure

        raise_on_failure(plan.system, plan.settings, follower.failed)
        raise AssertionError("the companion's loop took fewer steps than asked")
