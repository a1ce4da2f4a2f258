"""simulate(system, settings) -> Result: the time grid, the load on it, and the compiled loop.

The loop runs one chunk of steps at a time; every chunk's rows pass through the run's
reductions (extremes, plot data) and are kept in memory or streamed to a CSV file, so a
run's memory does not grow with its length.
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np

from rbhyst.solve import integrators
from rbhyst.solve.kernels import layout as kernels
from rbhyst.solve.kernels.compiled import jit_compiled, kernel
from rbhyst.errors import AnalysisError, InputError, byte_size
from rbhyst.solve.history import (Extremes, Layout, PlotData, Raw, body_spectrum_columns, estimate_columns,
                                  fold_extremes)
from rbhyst.solve.kernels.layout import N_STATE, N_W, X_CUR, X_ITER, X_LEVEL_USED, X_OMEGA_DT2, X_STEPS, X_SUBSTEPS, n_x, x_slice
from rbhyst.model.kinematics import loads_at
from rbhyst.model.system import System
from rbhyst.solve.result import Result, RunStats
from rbhyst.solve.static import at_rest_under_gravity
from rbhyst.solve.stops import element_forces, stop_record
from rbhyst.model.settings import Settings, settings_from_deck  # noqa: F401  (re-exported: the run's inputs)

#: bytes of rows a chunk may hold (raw state and table): bounds a run's memory
CHUNK_BYTES = 16_000_000
#: at most this many values (rows x columns) of a run are kept for its error estimate (every k-th row)
COMPARE_VALUES = 4_000_000


def grid(system: System, s: Settings) -> tuple[int, int]:
    """(output steps, the most compute steps per output step): an excitation finer than dt is
    followed, not aliased (see Excitation.substeps)."""
    n_steps = output_steps(system, s)
    return n_steps, int(splitting(system, s, n_steps)[1].max())


def splitting(system: System, s: Settings, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(bounds, substeps): output steps bounds[i]..bounds[i + 1] take substeps[i] compute steps
    each, those that follow the excitation (Excitation.substeps) times ``s.refine``, the
    refinement that meets the accuracy (rbhyst.solve.choose)."""
    bounds, substeps = system.excitation.substeps(s.dt, n_steps)
    return bounds, substeps * s.refine if s.refine > 1 else substeps


def output_steps(system: System, s: Settings) -> int:
    duration = s.duration if s.duration is not None else system.excitation.duration
    if duration is None:
        raise InputError("analysis.duration: required when no record or finite pulse gives it")
    if s.dt > duration:
        raise InputError(f"analysis.dt: {s.dt} s is larger than the duration {duration} s")
    steps = duration / s.dt
    if steps > MAX_COMPUTE_STEPS:  # (before any array of them: numbers past int64 overflow)
        raise InputError(f"analysis.duration, analysis.dt: {steps:.3g} steps of {s.dt:g} s ({duration:.4g} s) is "
                         f"beyond any analysis (more than {MAX_COMPUTE_STEPS:.0e} steps): shorten analysis.duration")
    return max(1, math.ceil(steps - 1e-9))


def compute_times(bounds: np.ndarray, substeps: np.ndarray, dt: float) -> np.ndarray:
    """Every compute step's end time after t = 0 where output steps bounds[i]..bounds[i + 1]
    take substeps[i] compute steps each (Excitation.substeps): the resolution at which a run
    follows its excitation, and at which its response spectra are driven."""
    if len(substeps) == 1 and substeps[0] == 1:  # (every step whole: t_n = n dt, the common case)
        return dt * np.arange(bounds[0] + 1, bounds[1] + 1, dtype=float)
    # (k / m of whole steps counted from 0: a node's time does not depend on where a chunk starts)
    parts = [dt * ((lo * m + np.arange(1, (hi - lo) * m + 1)) / m)
             for lo, hi, m in zip(bounds[:-1], bounds[1:], substeps)]
    return np.concatenate(parts) if parts else np.empty(0)


def compare_stride(layout: Layout, compute_steps: int) -> int:
    """Every how many compute steps a run's estimate compares its columns (time and
    history.estimate_columns): every one, or as many as keep them within COMPARE_VALUES."""
    nodes = compute_steps + 1
    return max(1, -(-nodes * (1 + len(estimate_columns(layout))) // COMPARE_VALUES))


class Rows:
    """Where a run's rows go: reductions over every compute step, every ``every``-th output row
    kept or streamed, the columns its error estimate compares at every ``compare_every``-th
    compute step, and the response spectra of G and the points at every compute step."""

    def __init__(self, layout: Layout, n_steps: int, every: int, keep: bool, csv=None,
                 spectra=None, dt: float | None = None, compare_every: int | None = None,
                 compute_steps: int | None = None):
        """csv: where the written rows also go, a function of the column names that opens a
        writer (``add(rows)``, ``close()``, ``path``; rbhyst.results.writers.CsvWriter), or None;
        spectra: what makes the sink of the spectra to stream from their labels (body_sink), for
        rows ``dt`` apart (or as :meth:`add` says); None for none. compute_steps: of the whole
        run, where steps of dt are split (Plan.compute_steps; n_steps where they are not)."""
        self.layout = layout
        self.every = every
        self.dt = dt
        self.extremes = Extremes(layout.names)
        # (a run that keeps neither its rows nor a folder of them has nothing to draw: a sweep's case)
        self.plot = PlotData(n_steps + 1, len(layout.names), drawn=keep or csv is not None)
        # the kept rows, allocated once and column by column (as Layout.table writes them): no
        # chunk is copied twice, and a column (Result.column, to_pandas) is contiguous
        n_rows = n_steps // every + 1
        self._kept = np.empty((len(layout.names), n_rows)).T if keep else None
        self._csv = csv(layout.names) if csv is not None else None
        self._next = 0  # global index of the next row
        self._node = 0  # ... and of the next compute node's
        # the columns the error estimate compares (rbhyst.solve.estimate), at every compare_every-th
        # compute step: where a step of dt is split, its error between the rows is the run's too
        self._compare_columns = np.array([0] + [c for _, c, _ in estimate_columns(layout)])
        nodes = (compute_steps if compute_steps is not None else n_steps) + 1
        self.compare_every = compare_every or compare_stride(layout, nodes - 1)
        # (one array, column by column as the table, grown where more rows come than the run's
        # compute nodes: each column copied once, contiguously, and no stack of them at the end)
        self._compared = np.empty((len(self._compare_columns), -(-nodes // self.compare_every))).T
        self._n_compared = 0
        self.spectra = None
        if spectra is not None:
            located = body_spectrum_columns(layout)
            self._spectrum_columns = [c for _, c in located]
            self.spectra = spectra([label for label, _ in located])

    def add(self, raw: Raw, sub: int = 1) -> None:
        """Rows of consecutive steps; with ``sub`` > 1, rows of every compute step of dt / sub,
        of which every sub-th (the last of each output step) is an output row: the spectra and
        the extremes (every peak) see them all, everything else the output rows."""
        n = len(raw.t) // sub
        direct = self._kept is not None and self.every == 1 and sub == 1
        table = self.layout.table(raw, out=self._kept[self._next:self._next + n] if direct else None)
        if self.spectra is not None:  # every compute step, whatever output.every writes
            self.spectra.update(table[:, self._spectrum_columns], self.dt / sub, table[:, 0])
        self._keep_compared(table)
        self._node += len(table)
        if sub > 1:
            # the peaks of the motion, not of the rows: a step of dt split to follow a record or
            # a pulse has its peaks between the rows
            fold_extremes(np.asfortranarray(table), self.extremes)
            table = table[sub - 1::sub]
        self.plot.update(table, self.extremes, folded=sub > 1)
        first = (-self._next) % self.every
        written = table[first::self.every]
        if self._kept is not None and not direct:
            row = -(-self._next // self.every)  # the first kept row of this chunk
            self._kept[row:row + len(written)] = written
        if self._csv is not None:
            self._csv.add(written)
        self._next += len(table)

    def _keep_compared(self, table: np.ndarray) -> None:
        """The estimate's columns of every compare_every-th compute node of the chunk."""
        first = (-self._node) % self.compare_every
        picked = table[first::self.compare_every]
        lo, hi = self._n_compared, self._n_compared + len(picked)
        if hi > len(self._compared):
            grown = np.empty((self._compared.shape[1], 2 * hi)).T
            grown[:lo] = self._compared[:lo]
            self._compared = grown
        into = self._compared[lo:hi]
        for j, c in enumerate(self._compare_columns):  # (a column of the table is contiguous)
            into[:, j] = picked[:, c]
        self._n_compared = hi

    def body_spectra(self):
        """The LocatedSpectra of G and the points over every row so far (None without output.spectra)."""
        return None if self.spectra is None else self.spectra.result()

    @property
    def compared(self) -> np.ndarray:
        """(n, 1 + columns): time and the estimate's columns (history.estimate_columns) at every
        compare_every-th compute step."""
        return self._compared[:self._n_compared]

    @property
    def csv_path(self):
        return None if self._csv is None else self._csv.path

    def close(self) -> np.ndarray | None:
        if self._csv is not None:
            self._csv.close()
        if self._kept is None:
            return None
        return self._kept[:-(-self._next // self.every)]  # every row, unless the run stopped early


def simulate(system: System, s: Settings, keep: bool = True, csv=None) -> Result:
    """Integrate M q'' + C q' + R(q) = p(t) from rest with the chosen method (seed eq. 11), for a
    body of any number of coordinates (system.n).

    keep: hold the written rows in memory (Result.table); csv: stream them to the writer it
    opens (see :class:`Rows`).
    """
    return prepare(system, s).run(keep=keep, csv=csv)


def prepare(system: System, s: Settings) -> "Plan":
    """Check the grid, build the method's coefficients and load its compiled kernel: what a
    run needs before it writes anything."""
    method = integrators.get(s.integrator)
    system = at_rest_under_gravity(system)
    n_steps = output_steps(system, s)
    if n_steps < s.every:
        raise InputError(f"output.every: {s.every} is more than the {n_steps} steps of the analysis")
    if method.solve is not None:
        return Plan(system, s, method)
    return FixedStepPlan(system, s, method)


#: more compute steps than this is not an analysis anyone means (hours of time stepping)
MAX_COMPUTE_STEPS = 10**10
#: rows kept in memory (rbhyst.run without out=) may take at most this many bytes
MAX_KEPT_BYTES = 2 * 1024**3
#: bytes of time_history.csv per value: 10 significant digits, sign, exponent, separator
CSV_BYTES_PER_VALUE = 16
#: a CSV larger than this is said before the run starts, with the output.every that keeps it
#: under SMALL_CSV_BYTES
LARGE_CSV_BYTES = 1e9
SMALL_CSV_BYTES = 1e8


class Plan:
    """A run ready to go. This one hands over to a method with a solver of its own."""

    def __init__(self, system: System, s: Settings, method):
        self.system, self.settings, self.method = system, s, method
        self.n_steps = output_steps(system, s)
        # runs of output steps split alike (Excitation.substeps), and the most compute steps a step
        self.bounds, self.substeps = splitting(system, s, self.n_steps)
        self.nsub = int(self.substeps.max())
        self.compute_steps = int(np.sum(np.diff(self.bounds) * self.substeps))  # (the rows of a tap, a companion)

    def check_size(self, keep: bool, folder=None) -> list[str]:
        """Refuse, before anything runs, what cannot fit: rows kept in memory beyond
        MAX_KEPT_BYTES, a CSV larger than the free disk, an absurd number of steps. Returns
        what to say before it starts: a CSV beyond LARGE_CSV_BYTES, and the output.every that
        would keep it under SMALL_CSV_BYTES."""
        import shutil
        from pathlib import Path

        s = self.settings
        steps = self.n_steps * self.nsub
        where = "analysis.duration, analysis.dt"
        if steps > MAX_COMPUTE_STEPS:
            raise InputError(f"{where}: {self.n_steps:.3g} steps of {s.dt:g} s ({self.n_steps * s.dt:.4g} s) "
                             f"{f'x {self.nsub} substeps ' if self.nsub > 1 else ''}is beyond any analysis "
                             f"(more than {MAX_COMPUTE_STEPS:.0e} steps): shorten analysis.duration")
        rows = self.n_steps // s.every + 1
        n_cols = len(Layout(self.system, s.points).names)
        need = rows * n_cols * CSV_BYTES_PER_VALUE
        every_for = lambda budget: max(s.every, -(-self.n_steps * n_cols * CSV_BYTES_PER_VALUE // max(int(budget), 1)))
        if folder is not None:
            probe = Path(folder)
            while not probe.exists() and probe != probe.parent:
                probe = probe.parent
            free = shutil.disk_usage(probe).free
            if need > 0.9 * free:
                raise InputError(
                    f"{folder}: {where}, output.every: the run would write {rows:.4g} rows of {n_cols} columns "
                    f"(about {byte_size(need)} of time_history.csv) with {byte_size(free)} free on the folder's "
                    f"disk: output.every = {every_for(int(0.5 * free))} or a shorter analysis.duration would fit")
        if keep and rows * n_cols * 8 > MAX_KEPT_BYTES:
            raise InputError(
                f"{where}, output.every: keeping {rows:.4g} rows of {n_cols} columns in memory takes "
                f"{rows * n_cols * 8 / 1e9:.3g} GB: stream them to a folder instead (rbhyst.run(deck, out=...)), "
                f"or raise output.every (to {every_for(MAX_KEPT_BYTES // 2)} or more)")
        if folder is not None and need > LARGE_CSV_BYTES:
            return [f"output: time_history.csv will take about {need / 1e9:.3g} GB ({rows:.4g} rows of {n_cols} "
                    f"columns); output.every = {every_for(SMALL_CSV_BYTES)} keeps it under "
                    f"{SMALL_CSV_BYTES / 1e6:.0f} MB (peaks, extremes and spectra still see every step)"]
        return []

    def run(self, keep: bool = True, csv=None, compare_every: int | None = None, progress=None,
            tap=None) -> Result:
        """``progress(done, total, label)``, if given, hears how far the run is (``tap``: see
        FixedStepPlan.run)."""
        if progress is not None:
            progress(0, 0, f"{self.settings.integrator}: adaptive integration")
        return self.method.solve(self.system, self.settings, keep=keep, csv=csv)


class FixedStepPlan(Plan):
    """A fixed-step method in the compiled loop (rbhyst.solve.kernels.loop).

    Each output step k is split into ``substeps[k]`` compute steps where a signal needs it
    (Excitation.substeps); each distinct split has its own coefficients and K0 substep level.
    """

    def __init__(self, system: System, s: Settings, method):
        super().__init__(system, s, method)
        mass = system.mass
        self.minv = 1.0 / mass
        self.cm = np.ascontiguousarray(system.kernel_damping)  # (C, and turning dampers' rows: exact kinematics)
        self.damped = bool(np.any(self.cm != 0.0))
        self.K0 = k0 = np.ascontiguousarray(system.K0, dtype=float)  # (the system works it out at every call)
        self.coef, self.level0 = {}, {}
        for nsub in np.array(sorted(set(self.substeps.tolist())), dtype=np.int64):  # (np.unique imports numpy.ma)
            h_c = s.dt / nsub
            level0 = min_level(system, s, method, h_c)
            # levels below level0 are never used (and may be singular for an extreme K0)
            steps = np.array([h_c / 2**max(lv, level0) for lv in range(s.max_substep_level + 1)])
            self.coef[int(nsub)] = method.coefficients(mass, k0, self.cm[:system.n], steps)  # (one set a level)
            self.level0[int(nsub)] = level0
        self.bvec = np.ascontiguousarray(system.bvec)
        self.params = system.kernel_params  # (with each stop's row where there are stops)
        self.axial = system.kernel_axial
        # the monitor's trace bound, b_e^T M^-1 b_e: with exact kinematics the rotation's entry of
        # b_e(q) turns between +-sqrt(b3^2 + axial^2), its largest taken
        rows = self.bvec.copy()
        if system.rotation_index >= 0:
            rows[:, system.rotation_index] = np.hypot(rows[:, system.rotation_index], self.axial)
        self.wgt = (rows * rows) @ self.minv
        # (in space with exact rotations the loop rewrites it at every step from the rows it reached)
        ne = self.bvec.shape[0]
        self.layout = Layout(system, s.points)
        per_chunk = _chunk_rows(ne, system.n, len(self.layout.names), self.nsub)
        self.chunk = min(per_chunk, self.n_steps)
        # compute-step rows (``fine``) a chunk holds: as many as the memory bound allows, so that
        # a short run takes one call of the loop a segment (a chunk's Python costs some 30 us)
        self.fine_chunk = min(per_chunk, self.compute_steps)
        self._initial = None  # (initial_state, computed once)
        # the loop for n coordinates, loaded (or compiled) once, and M and M^-1 as tuples: their
        # length n is then a constant of the compiled loop (one compilation per n), which
        # unrolls every loop over the coordinates
        self._loop = kernel("run_chunk", self.bvec.shape[1])
        self._mass, self._minv = tuple(system.mass), tuple(self.minv)
        if jit_compiled(self._loop):  # compiled (or loaded from numba's cache) now, not in the first chunk's time
            nsub = next(iter(self.coef))
            self._call(np.zeros((1, system.n)), 0.0, nsub, s.dt / nsub, nsub, 0, *self.initial_state(),
                       _Buffers(1, ne, system.n))

    def initial_state(self):
        """The loop's state at t = 0: at rest, elements virgin, and the initial acceleration (new
        arrays: the loop steps them in place)."""
        if self._initial is None:
            self._initial = self._state_at_rest()
        x, st = self._initial
        return x.copy(), st.copy()

    def _state_at_rest(self):
        from rbhyst.model.system import stiffnesses_at_zero

        ne, n = self.bvec.shape
        x = np.zeros(n_x(n))
        st = np.zeros((2, ne, N_STATE))
        # virgin elements: u = f = 0 and no branch yet (S = 0), so the first move starts a branch
        # whatever its direction; until it moves, an element's tangent is the stiffer of its two
        # first moves, so the monitor sees a stiff body at rest before the first step that moves it
        for e in range(ne):
            st[0, e, kernels.K] = stiffnesses_at_zero(self.system.params[e])[2]
        static = self.system.static
        q0 = static.q if static is not None else np.zeros(n)
        p0 = loads_at(self.system.excitation.load(np.zeros(1), self.system.mass), q0[None], n,
                      self.system.rotation_index, self.axial)[0]
        if static is not None:  # at rest at the static equilibrium under gravity, its branches as the path left them
            st[0] = static.st
            st[0, :, kernels.UP] = st[0, :, kernels.U]  # (no step before the first)
            # the stops' record is the run's: a contact the weight rests on has not struck
            st[0, :, [kernels.IMP, kernels.NI, kernels.PF, kernels.PD]] = 0.0
            x[x_slice(n, 0)] = static.q
            p0 = p0 - static.r
        x[x_slice(n, 2)] = self.minv * p0  # equilibrium at t = 0: records rarely start at zero
        x[X_CUR] = 0
        return x, st

    def _call(self, load, t0, nsub, h_c, rows_every, n, x, st, buf, rot=None, levels=None, force=False, info=None):
        """n rows of the loop: compute steps of h_c with the coefficients of ``nsub`` substeps a
        step of dt, a row after every ``rows_every``-th of them (``rot``: the kinematics' code,
        if not the system's: kernels.layout.LOCATED). ``levels`` (compute steps,): receives each
        step's substep level; with ``force`` each step takes the level it holds. ``info``
        (kernels.INFO_SIZE,): receives how the loop ended, the caller's own (two threads may
        step one plan: an estimate's companion and its probe)."""
        s = self.settings
        ne, n_q = self.bvec.shape
        if n > len(buf.d):  # the compiled loop checks no bounds: never let it write past a buffer
            raise RuntimeError(f"a chunk of {n} rows does not fit its buffers of {len(buf.d)}")
        if info is None:
            info = np.zeros(kernels.INFO_SIZE)
        if levels is None:
            levels = np.empty(n * rows_every, dtype=np.int64)
        if len(levels) < n * rows_every:
            raise RuntimeError(f"{len(levels)} levels for a chunk of {n * rows_every} compute steps")
        return self._loop(self.method.kernel_id, self.coef[nsub], self._mass, self._minv, self.cm, self.damped,
                          self.bvec, self.axial, self.system.rotation_index if rot is None else rot, self.system.mult,
                          self.params, self.wgt, load,
                          t0, h_c, rows_every, n, s.max_omega_dt, self.level0[nsub], s.max_substep_level,
                          s.newton_tol, s.newton_max_iter, x, st, np.zeros((ne, N_STATE)), np.zeros((ne, 2)),
                          np.zeros((ne, n_q)), np.zeros((N_W, n_q)), np.zeros((n_q, n_q)), buf.d, buf.v, buf.u, buf.f, buf.e,
                          buf.fb, levels, force, info)

    def compared_nodes(self, every: int) -> slice:
        """Every ``every``-th compute node from t = 0 (the rows a run's estimate compares:
        Rows.compare_every)."""
        return slice(0, (self.compute_steps // every) * every + 1, every)

    @functools.cached_property
    def rb(self) -> np.ndarray:
        """(kernel rows, n) each row's share of the mounts' resultant R = sum mult b f (the seed's
        small rotations)."""
        return np.ascontiguousarray(self.bvec * self.system.mult[:, None])

    def segments(self, fine: bool = False):
        """(first output step, steps, substeps each): runs of equal splitting, at most a chunk of
        rows long (of compute-step rows where ``fine``)."""
        for lo, hi, nsub in zip(self.bounds[:-1], self.bounds[1:], self.substeps):
            chunk = max(1, self.fine_chunk // int(nsub)) if fine else self.chunk
            for k in range(int(lo), int(hi), chunk):
                yield k, min(chunk, int(hi) - k), int(nsub)

    def start_row(self, x: np.ndarray, st: np.ndarray) -> Raw:
        """The row at t = 0 of the state initial_state gives."""
        n = self.system.n
        return Raw(t=np.zeros(1), d=x[None, x_slice(n, 0)].copy(), v=np.zeros((1, n)),
                   u=st[None, 0, :, kernels.U].copy(), f=element_forces(st[0])[None],
                   e=np.zeros((1, kernels.N_E)))

    def chunks(self, x: np.ndarray, st: np.ndarray, fine: bool = False, into=None):
        """Step the loop from the state (x, st) to the end, chunk by chunk: yields (first output
        step, output steps, substeps each, the chunk's load at its compute nodes, its rows (every
        compute step where ``fine``), each compute step's substep level, kernel seconds).
        ``into``: where the rows of every compute step go (``fine``), ``into.buffers(node,
        rows)`` giving a chunk's arrays from its first compute node on (the rows of a whole run
        kept without a copy: the estimate's tap)."""
        system, s = self.system, self.settings
        ne, n = self.bvec.shape
        # a chunk of compute-step rows holds at least one output step's substeps (a pulse far
        # shorter than dt splits one step into more rows than a chunk of a short run has)
        if into is None:
            buf = _Buffers(max(self.fine_chunk, int(self.substeps.max())) if fine else self.chunk, ne, n)
        node = 0  # the compute node the chunk starts at
        for first, n_out, nsub in self.segments(fine):
            t_c = s.dt * ((first * nsub + np.arange(n_out * nsub + 1)) / nsub)  # (as compute_times)
            load = np.ascontiguousarray(system.excitation.load_nodes(t_c, s.dt / nsub, system.mass))
            steps = n_out * nsub
            level = np.empty(steps, dtype=np.int64)
            if into is not None:
                assert fine, "rows kept at every compute step are fine rows"
                buf = into.buffers(node, steps)
            node += steps
            sub = nsub if fine else 1
            info = np.zeros(kernels.INFO_SIZE)
            tic = time.perf_counter()
            written = self._call(load, s.dt * first, nsub, s.dt / nsub, nsub // sub, n_out * sub, x, st, buf,
                                 levels=level, info=info)
            wall = time.perf_counter() - tic
            raise_on_failure(system, s, info)
            assert written == n_out * sub, "the loop wrote fewer rows than asked"
            t = t_c[1:] if sub > 1 else s.dt * (first + 1 + np.arange(n_out))  # t_n = n dt, never accumulated
            m = n_out * sub
            yield first, n_out, nsub, load, Raw(t=t, d=buf.d[:m], v=buf.v[:m], u=buf.u[:m], f=buf.f[:m],
                                                 e=buf.e[:m]), level, wall

    def step_through(self, x: np.ndarray, st: np.ndarray, load: np.ndarray, levels: np.ndarray, rows,
                     rot: int | None = None) -> tuple[float, np.ndarray]:
        """Step the loop from the state (x, st) to the end as a run stepped: each compute step at
        the substep level ``levels`` holds (a run's, as it took them; only Newton's failure
        splits a step further), under ``load`` at every compute node, a row after every step,
        in one call of the compiled loop (kernels.through). ``rows.arrays(scratch)`` gives the
        arrays the rows go into (the estimate's companion and its probe: rbhyst.solve.companion's
        KeptRows, PickedRows), ``scratch`` the rows a segment's own may need. ``rot``: a
        kinematics' code other than the system's. Returns the kernel seconds and the levels the
        steps took."""
        s = self.settings
        ne, n_q = self.bvec.shape
        segments, coefs, scratch = self._through
        through = kernel("step_through", n_q)
        d, v, u, f, e, fb, whole, take, pick_d, pick_v, pick_f = rows.arrays(scratch)
        nodes = len(levels) + 1
        # the compiled loop checks no bounds: never let it write past an array
        for out, kept in zip((d, v, u, f), whole):
            if len(out) < (nodes if kept else scratch):
                raise RuntimeError(f"{len(out)} rows for {nodes if kept else scratch}")
        if len(load) < nodes or len(e) < scratch or (len(take) and (take[-1] >= nodes or len(pick_d) <= len(take))):
            raise RuntimeError("the arrays do not hold the run's rows")
        taken = levels.copy()
        info = np.zeros(kernels.INFO_SIZE)
        tic = time.perf_counter()
        done = through(self.method.kernel_id, coefs, self._mass, self._minv, self.cm, self.damped, self.bvec,
                       self.axial, self.system.rotation_index if rot is None else rot, self.system.mult, self.params,
                       self.wgt, load, segments, s.dt, s.max_omega_dt, s.max_substep_level, s.newton_tol,
                       s.newton_max_iter, x, st, np.zeros((ne, N_STATE)), np.zeros((ne, 2)), np.zeros((ne, n_q)),
                       np.zeros((N_W, n_q)), np.zeros((n_q, n_q)), d, v, u, f, e, fb, whole, take, pick_d, pick_v,
                       pick_f, taken, True, info)
        wall = time.perf_counter() - tic
        raise_on_failure(self.system, s, info)
        assert done == nodes - 1, "the loop took fewer steps than asked"
        return wall, taken

    @functools.cached_property
    def _through(self):
        """(segments, coefficients, rows) of step_through: the fine segments as a table (first
        output step, output steps, substeps each, their coefficients' row, level0), every
        splitting's coefficients stacked, and the most compute steps of a segment."""
        order = sorted(self.coef)
        rows = [(first, n_out, nsub, order.index(nsub), int(self.level0[nsub]))
                for first, n_out, nsub in self.segments(fine=True)]
        segments = np.array(rows, dtype=np.int64).reshape(-1, 5)
        coefs = np.empty((len(order), *self.coef[order[0]].shape))
        for k, nsub in enumerate(order):
            coefs[k] = self.coef[nsub]
        return segments, coefs, max(n_out * nsub for _, n_out, nsub, _, _ in rows)

    def run(self, keep: bool = True, csv=None, compare_every: int | None = None, progress=None,
            tap=None) -> Result:
        """``tap(load, raw, levels)``, if given, sees every chunk's load at its compute nodes, its
        rows (in the arrays ``tap.buffers`` gives: plan.chunks' ``into``) and the substep level
        of each step (the error estimate's companion: rbhyst.solve.companion)."""
        system, s = self.system, self.settings
        ne, n = self.bvec.shape
        x, st = self.initial_state()
        spectra = s.spectra is not None
        # the spectra, the peaks and a tap see every compute step where a step of dt is split (a
        # short pulse's response between the rows)
        fine = spectra or tap is not None or self.nsub > 1
        rows = Rows(self.layout, self.n_steps, s.every, keep, csv, spectra=body_sink(system, s), dt=s.dt,
                    compare_every=compare_every, compute_steps=self.compute_steps)
        wall = 0.0
        try:
            rows.add(self.start_row(x, st))
            for first, n_out, nsub, load, raw, levels, took in self.chunks(x, st, fine, into=tap):
                wall += took
                if tap is not None:
                    tap(load, raw, levels)
                rows.add(raw, sub=nsub if fine else 1)
                if progress is not None:
                    progress(first + n_out, self.n_steps, f"{s.integrator}: time stepping")
        finally:
            table = rows.close()
        stats = RunStats(
            steps=self.n_steps, record_substeps=self.nsub // s.refine, refine=s.refine,
            min_substep_level=max(self.level0.values()),
            substeps=int(x[X_SUBSTEPS]), max_substep_level=int(x[X_LEVEL_USED]),
            max_omega_dt=float(math.sqrt(x[X_OMEGA_DT2])), steps_taken=int(x[X_STEPS]),
            newton_iterations=int(x[X_ITER]) if self.method.name == "newmark" else 0, wall_s=wall,
        )
        return Result(system=system, settings=s, columns=self.layout.names, table=table, extremes=rows.extremes,
                      plot=rows.plot, stats=stats, layout=self.layout, csv_path=rows.csv_path, compared=rows.compared,
                      compare_every=rows.compare_every, spectra=run_spectra(system, s, rows.body_spectra()),
                      stops=stop_record(st[int(x[X_CUR])]) if system.has_stops else None)


class _Buffers:
    """One chunk of the loop's output rows."""

    def __init__(self, rows: int, ne: int, n: int):
        self.d = np.empty((rows, n))
        self.v = np.empty((rows, n))
        self.u = np.empty((rows, ne))
        self.f = np.empty((rows, ne))
        self.e = np.empty((rows, kernels.N_E))
        self.fb = np.empty(ne)  # (the row before the chunk's: kept by none of these)


def body_sink(system: System, s: Settings):
    """What makes the sink of the body's spectra from their labels (None without output.spectra)."""
    if s.spectra is None:
        return None
    if s.spectra_kind == "srs":  # primary up to the excitation's end, residual after
        from rbhyst.solve.located_shock import ShockSink, excitation_end

        return lambda labels: ShockSink(labels, *s.spectra, dt=s.dt, switch=excitation_end(system.excitation))
    from rbhyst.solve.located import SpectraSink

    return lambda labels: SpectraSink(labels, *s.spectra, dt=s.dt)


def run_spectra(system: System, s: Settings, body):
    """The run's LocatedSpectra (LocatedShockSpectra with kind "srs"): the ground's, from its
    signals themselves (rbhyst.solve.ground), and the body's (G and the points) as the rows drove
    them; None without output.spectra."""
    if body is None:
        return None
    n_steps = output_steps(system, s)
    if s.spectra_kind == "srs":
        from rbhyst.solve.located_shock import ground_shock_spectra

        return ground_shock_spectra(system.excitation, n_steps * s.dt, *s.spectra).joined(body)
    from rbhyst.solve.ground import ground_spectra

    return ground_spectra(system.excitation, n_steps * s.dt, *s.spectra).joined(body)


def _chunk_rows(ne: int, n: int, n_cols: int, nsub: int) -> int:
    """Output steps per chunk: CHUNK_BYTES of raw rows, table rows and load."""
    per_row = 8 * (3 * n + 2 * ne + kernels.N_E + n_cols + n * nsub)
    return int(min(65_536, max(64, CHUNK_BYTES // per_row)))


def min_level(system: System, s: Settings, method, h: float) -> int:
    """Substep level that a structure-dependent method needs for omega_0 h <= the limit.

    Chang's displacement predictor scales the step's motion by (1 + (omega_0 h)^2 / 4)^-1
    where the tangent is softer than K0: accurate only while omega_0 h is small, whatever
    the current stiffness. omega_0^2 = max eig(M^-1 K0).
    """
    if not method.structure_dependent:
        return 0
    m = 1.0 / np.sqrt(system.mass)
    w0 = float(np.sqrt(np.max(np.linalg.eigvalsh(system.K0 * np.outer(m, m)))))
    level = max(0, math.ceil(math.log2(w0 * h / s.max_omega_dt))) if w0 * h > s.max_omega_dt else 0
    if level > s.max_substep_level:
        raise AnalysisError(
            f"omega_0 = {w0:.4g} rad/s of K0 (the elements' stiffness away from reversals) needs steps of "
            f"{s.max_omega_dt / w0:.3g} s with {s.integrator!r}: more than {2**s.max_substep_level} "
            f"substeps of dt = {s.dt:g} s; dt = {s.max_omega_dt / w0 * 2**s.max_substep_level:.3g} s would do "
            "(or a stiffer body is an input mistake: check the mass and kb)"
        )
    return level


def _element_name(system: System, row: int) -> str:
    """'element e3' or 'elements e3, e4, e7' (CSV numbers) with the first one's place (deck frame)."""
    numbers = system.row_elements(row)
    el = next(el for el in system.elements if el.row == row)
    g = system.body.mass_centre
    span = ("element " if len(numbers) == 1 else "elements ") + ", ".join(f"e{k}" for k in numbers)
    where = ", ".join(f"{x + c:.4g}" for x, c in zip(el.x, g))
    return f"{span} ({el.hysteresis!r} at ({where}) m, {el.line})"


#: an exponential term that has grown beyond e^this has left any calibrated range
EXP_RANGE = 20.0


def raise_on_failure(system: System, s: Settings, info: np.ndarray) -> None:
    status = int(info[kernels.I_STATUS])
    if status == kernels.OK:
        return
    t = info[kernels.I_TIME]
    e = int(info[kernels.I_ELEMENT])
    if status == kernels.OVERFLOW:
        p = system.params[e]
        raise AnalysisError(
            f"t = {t:.6g} s: {_element_name(system, e)} left its calibrated range: "
            f"beta2 u exceeded {700:g} (beta2 = {p[0, 4]:g}, {p[1, 4]:g} 1/m), so its force would overflow"
        )
    if status == kernels.UNRESOLVED:
        omega = info[kernels.I_OMEGA]
        k = info[kernels.I_STIFFNESS]
        u = info[kernels.I_DISP]
        p = system.params[e]
        row = 0 if info[kernels.I_BRANCH] > 0 else 1
        b1, b2 = p[row, 3], p[row, 4]
        if b1 != 0.0 and b2 * u > EXP_RANGE:
            raise AnalysisError(
                f"t = {t:.6g} s: {_element_name(system, e)} is driven to u = {u:.4g} m, where its term "
                f"beta1 e^(beta2 u) (beta2 = {b2:g} 1/m) has grown by e^{b2 * u:.3g} and its stiffness to "
                f"{k:.4g} N/m: beta2 is out of range for this motion (no step can follow it, and no "
                "calibration reaches that far); check the set's beta2 and the deck's units"
            )
        raise AnalysisError(
            f"t = {t:.6g} s: {_element_name(system, e)} reached a tangent stiffness of {k:.4g} N/m "
            f"(omega_max = {omega:.4g} rad/s), which {2**s.max_substep_level} substeps of "
            f"dt = {s.dt:g} s cannot resolve; a step of {s.max_omega_dt / omega:.3g} s "
            "would (or raise analysis.max_substep_level)"
        )
    if status == kernels.NOT_CONVERGED:
        raise AnalysisError(
            f"t = {t:.6g} s: Newton iterations of {s.integrator!r} did not converge to "
            f"{s.newton_tol:g} in {s.newton_max_iter} iterations, even with {2**s.max_substep_level} "
            f"substeps of dt = {s.dt:g} s; reduce dt or use an explicit integrator"
        )
    raise AnalysisError(
        f"t = {t:.6g} s: the solution is no longer finite (NaN or Inf); the scene is numerically "
        f"unstable at dt = {s.dt:g} s with {s.integrator!r}"
    )
