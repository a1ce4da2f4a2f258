"""The time-history table of a run, built chunk by chunk from what an integrator computes.

An integrator hands over :class:`Raw` chunks (the state at every step of dt); a
:class:`Layout` turns each into rows of time_history.csv's columns; :class:`Extremes` and
:class:`PlotData` reduce every row as it passes, so that peaks, extremes and plots see
every computed step whatever ``output.every`` keeps, and a run of any length needs one
chunk in memory.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from rbhyst.model.coordinates import PLANE, columns, translations
from rbhyst.model.kinematics import SPATIAL, point_motion_exact, turned_loads
from rbhyst.solve.kernels.compiled import kernel
from rbhyst.solve.kernels.layout import SMALL
from rbhyst.model.points import point_columns, point_matrix, point_motion


def base_columns(coordinates=PLANE) -> tuple[str, ...]:
    """time, then the displacements, velocities, relative and total accelerations of q:
    ``time_s, u1_m, u2_m, theta3_rad, v1_m_s, ..., alphat3_rad_s2`` for the plane body."""
    return ("time_s", *(name for family in ("d", "v", "a", "at") for name in columns(coordinates, family)))


BASE_COLUMNS = base_columns(PLANE)
SUPPORT_COLUMNS = ("ag1_m_s2", "ag2_m_s2")
RESULTANT_COLUMNS = tuple(columns(PLANE, "R"))
ENERGY_COLUMNS = ("E_input_J", "E_kinetic_J", "E_hysteretic_J", "E_error_J")
VISCOUS_COLUMN = "E_viscous_J"


@dataclass
class Raw:
    """What an integrator computed at consecutive steps: times (n,), displacements and
    velocities (n, len(q)) each, element rows' deformation and force (n, rows), cumulative
    energies (n, 4): input, kinetic, hysteretic, viscous. Accelerations are not an
    integrator's to report: :class:`Layout` takes them from the equation of motion."""

    t: np.ndarray
    d: np.ndarray
    v: np.ndarray
    u: np.ndarray
    f: np.ndarray
    e: np.ndarray

    def slice(self, start: int, stop: int | None, step: int = 1) -> "Raw":
        """Rows start..stop-1 (every step-th)."""
        return Raw(*(getattr(self, k)[start:stop:step] for k in ("t", "d", "v", "u", "f", "e")))


def largest_abs(x: np.ndarray) -> np.ndarray:
    """max_t |x| of every column of (rows, k): column by column in memory (numpy reduces a
    C-ordered array of a few columns down its rows some thirty times slower), no |x| array."""
    if len(x) == 0:
        return np.zeros(x.shape[1])
    x = np.asfortranarray(x)
    return np.maximum(x.max(axis=0), -x.min(axis=0))


def rows_times(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a @ b (a: rows, k; b: k, m), each row summed in the same order whatever the number of
    rows (kernels.reduce.resultant): BLAS sums a single row in another order than a block on
    some processors, and a run's rows would depend on where its chunks start."""
    out = np.empty((len(a), b.shape[1]))
    kernel("resultant")(a, b, out)
    return out


def shear_lines(system) -> list[tuple[int, list[int], np.ndarray]]:
    """Each MSS isolator (rbhyst.model.mss) as (its deck number, its springs' output elements
    (0-based, the first of its ``count``), (2, n) the cosines of their lines to its two shear
    lines); empty where there are none."""
    groups: dict[int, list[int]] = {}
    k = 0
    for el in system.elements:
        if el.role is not None and el.role.startswith("mss"):
            groups.setdefault(el.isolator, []).append(k)
        k += el.count
    if not groups:
        return []
    from rbhyst.model.mss import spring_cosines

    return [(iso, cols, np.array(spring_cosines(len(cols)))) for iso, cols in groups.items()]


class Layout:
    """Which columns a scene's table has and how a Raw chunk becomes rows of them."""

    def __init__(self, system, points=()):
        """points: (name, (x1, x2) in the deck's frame) of each point of interest (output.points)."""
        self.system = system
        ex = system.excitation
        coords = system.coordinates
        n = len(coords)
        self.has_support = ex.has_support
        self._forced = ex.has_forces  # (without, a row's forces are 0)
        self.dampers = bool(system.dampers)  # their columns
        self._turning = False
        # viscous work (and C v in the accelerations) with dampers or Rayleigh damping
        self.damped = self.dampers or getattr(system, "rayleigh", None) is not None
        names = list(base_columns(coords))
        self.slices: dict[str, slice] = {family: slice(1 + k * n, 1 + (k + 1) * n)
                                         for k, family in enumerate(("d", "v", "a", "at"))}
        # the translations of q: the directions a support moves and a point has
        self._moving = translations(coords)
        if self.has_support:
            self._axes = tuple(coords[i].axis for i in self._moving)
            # the horizontal axes always, x3 (vertical in space) where it has a signal
            self._shown = [c for c, k in enumerate(self._axes) if k < 3 or f"ag{k}" in ex.signals]
            self.slices["ag"] = slice(len(names), len(names) + len(self._shown))
            names += [f"ag{self._axes[c]}_m_s2" for c in self._shown]
        self.slices["R"] = slice(len(names), len(names) + n)
        names += columns(coords, "R")
        g = np.asarray(system.body.mass_centre, dtype=float)
        self.points = tuple((name, np.asarray(p, dtype=float) - g) for name, p in points)  # x from G
        self._point_width = 2 * len(self._moving)
        self.slices["points"] = slice(len(names), len(names) + self._point_width * len(self.points))
        for name, _ in self.points:
            names += point_columns(name, coords)
        n_el = system.n_output_elements
        self.slices["elements"] = slice(len(names), len(names) + 2 * n_el)
        for k in range(1, n_el + 1):
            names += [f"e{k}_u_m", f"e{k}_f_N"]
        # an MSS isolator's shear lines: deformation and the springs' resultant along each
        self._shear = shear_lines(system)
        if self._shear:
            self.slices["shear"] = slice(len(names), len(names) + 4 * len(self._shear))
            for k, _, _ in self._shear:
                names += [f"iso{k}_shear{j}_{q}" for j in (1, 2) for q in ("u_m", "f_N")]
        if self.dampers:
            n_d = len(system.damper_c)
            self.slices["dampers"] = slice(len(names), len(names) + 2 * n_d)
            for k in range(1, n_d + 1):
                names += [f"d{k}_v_m_s", f"d{k}_f_N"]
            self._db = system.damper_b.T.copy()  # (n, dampers): deformation rates v . b
            self._dc = system.damper_c
            # with exact kinematics their rows turn with the body (kinematics.damper_rows)
            self._turning = system.kinematics == "exact"
            self._dcount = np.array([dp.count for dp in system.dampers])
            self._dcc = np.array([dp.c * dp.count for dp in system.dampers])
        # displacements are measured from the static equilibrium under gravity (seed section 2.2)
        self.origin = np.zeros(n) if getattr(system, "static", None) is None else system.static.q
        energy = list(ENERGY_COLUMNS)
        if self.damped:
            energy.insert(3, VISCOUS_COLUMN)
        self.slices["energy"] = slice(len(names), len(names) + len(energy))
        names += energy
        self.names = tuple(names)
        self.coordinates = coords
        self._expand = np.array([el.row for el in system.elements for _ in range(el.count)], dtype=np.int64)
        self._rb = np.ascontiguousarray(system.bvec * system.mult[:, None], dtype=float)  # rows' share of R = sum mult b f
        # exact kinematics: the rotation's entry of b_e(q) is b3 cos(theta) - c sin(theta)
        self._rot = system.rotation_index
        self._rc = system.kernel_axial * system.mult if self._rot >= 0 else None
        self._rc_column = None if self._rc is None else np.ascontiguousarray(self._rc, dtype=float)[:, None].copy()
        self._minv = 1.0 / np.asarray(system.mass, dtype=float)
        self._ct = system.C.T.copy() if self.damped else None
        # a body that runs in its principal axes: its rows are turned back to the deck's
        frame = getattr(system, "frame", None)
        self._back = None if frame is None else np.asarray(frame, dtype=float).T.copy()
        if self._rot == SPATIAL:  # a body in space, exact (rbhyst.model.rotations)
            from rbhyst.model.rotations import matrices

            self._axial = system.kernel_axial
            self._p = np.eye(3) if frame is None else np.asarray(frame, dtype=float)[3:, 3:]
            # the attitude displacements are measured from (the static equilibrium's), deck axes
            self._r0 = matrices(self._p @ self.origin[3:6])[0]

    def index(self, name: str) -> int:
        return self.names.index(name)

    def table(self, raw: Raw, out: np.ndarray | None = None) -> np.ndarray:
        """Rows of the table for a chunk (every computed step of it), into ``out`` if given
        (n rows; column-major is fastest)."""
        n = len(raw.t)
        if out is None:
            out = np.empty((len(self.names), n)).T  # column by column: each written contiguously
        out[:, 0] = raw.t
        if self._rot == SPATIAL:
            return self._table_space(raw, out)
        out[:, self.slices["d"]] = raw.d - self.origin
        out[:, self.slices["v"]] = raw.v
        r = out[:, self.slices["R"]]
        r[:] = self.restoring(raw.f, raw.d)
        # the total acceleration from the equation of motion at the row's own state and time:
        # M at = p(t) - R - C v (the elements and dampers see only the relative motion, so it is
        # continuous where the support acceleration jumps; a jump of an external force: the row
        # holds the force's value on its span). Not the integrator's own acceleration, which
        # near a jump or a kink carries the load averaged over a step.
        at = out[:, self.slices["at"]]
        if self._forced:
            forces = self.system.excitation.forces(raw.t)
            if forces.shape[1] > len(self.coordinates):  # forces whose arm turns (exact kinematics)
                forces = turned_loads(forces, raw.d[:, self._rot], len(self.coordinates), self._rot)
            at[:] = forces - r
        else:  # (support motion alone: 0 - R, +0.0 where R is 0, as a zero force minus R gives)
            np.subtract(0.0, r, out=at)
        if self.damped:
            at -= self._viscous(raw)
        at *= self._minv
        if self._back is not None:
            for family in ("d", "v", "R", "at"):
                block = out[:, self.slices[family]]
                block[:] = rows_times(block, self._back)
        self._rest(raw, out, at)
        return out

    def restoring(self, f: np.ndarray, d: np.ndarray) -> np.ndarray:
        """(rows, n) the mounts' resultant R = sum mult b_e(q) f_e from the kernel rows' forces f at
        the coordinates d (the plane: small or exact rotations)."""
        r = rows_times(f, self._rb)
        if self._rot >= 0:
            th = d[:, self._rot]
            r[:, self._rot] = np.cos(th) * r[:, self._rot] - np.sin(th) * rows_times(f, self._rc_column)[:, 0]
        return r

    def largest_change(self, dd: np.ndarray, dv: np.ndarray, df: np.ndarray) -> np.ndarray:
        """(k,) the largest change over the rows of every estimate column (estimate_columns) that
        changes of the coordinates, velocities and element forces (dd, dv, df: the kernels'
        rows) make at the same times: the table is linear in them with the seed's small
        rotations (the load, the support and the origin cancel). What the error estimate's
        companion compares (rbhyst.solve.companion), in one compiled pass over the rows
        (kernels.reduce.largest_change)."""
        assert self._rot == SMALL, "the table is linear in the state only with small rotations"
        n = dd.shape[1]
        arms, ct, back = self._change_terms
        top = np.empty(3 * n + 2 * arms.shape[1] * arms.shape[0] + df.shape[1])
        kernel("largest_change")(dd, dv, df, self._rb, ct, self.damped, self._minv, back, self._back is not None, arms,
                                 top, np.empty((4, n)))
        return self.expand_change(top)

    def expand_change(self, top: np.ndarray) -> np.ndarray:
        """largest_change's columns from its kernel's: every kernel row's force to each output
        element's (an element that shares its row with another has its change)."""
        body = len(top) - self._rb.shape[0]
        return np.concatenate([top[:body], top[body:][self._expand]])

    @functools.cached_property
    def _change_terms(self):
        """largest_change's constant arrays: every point's T(x) (points, translations, n), C^T and
        the turn back to the deck's axes (zeros and the identity where there are none)."""
        n = len(self.coordinates)
        arms = np.zeros((len(self.points), len(self._moving), n))
        for k, (_, x) in enumerate(self.points):
            arms[k] = point_matrix(x, self.coordinates)
        ct = np.ascontiguousarray(self._ct) if self._ct is not None else np.zeros((n, n))
        back = np.ascontiguousarray(self._back) if self._back is not None else np.eye(n)
        return arms, ct, back

    def _rest(self, raw: Raw, out: np.ndarray, at: np.ndarray, omega=None) -> None:
        """The columns after G's motion, resultant and total acceleration (in the deck's axes in
        ``out``; ``at`` their block): relative accelerations, the support, points, elements,
        dampers, energies. omega: a body in space with exact kinematics, its angular velocity
        in the deck's axes (its points move exactly)."""
        rel = out[:, self.slices["a"]]
        rel[:] = at
        if self.has_support:
            ag = self.system.excitation.support(raw.t, self._axes)
            for c, i in enumerate(self._moving):
                rel[:, i] -= ag[:, c]
            out[:, self.slices["ag"]] = ag if len(self._shown) == len(self._axes) else ag[:, self._shown]
        first = self.slices["points"].start
        for k, (_, x) in enumerate(self.points):
            c = first + self._point_width * k
            if omega is not None:
                from rbhyst.model.rotations import point_motion_space

                d = out[:, self.slices["d"]].copy()
                d[:, 3:6] = raw.d[:, 3:6] @ self._p.T  # the attitude itself, not its turn from rest
                point_motion_space(d, at, omega, x, self._r0, out=out[:, c:c + self._point_width])
            elif self._rot >= 0:
                point_motion_exact(out[:, self.slices["d"]], raw.v, at, x, raw.d[:, self._rot],
                                   float(self.origin[self._rot]), out=out[:, c:c + self._point_width])
            else:
                point_motion(out[:, self.slices["d"]], at, x, out=out[:, c:c + self._point_width],
                             coordinates=self.coordinates)
        el = self.slices["elements"]
        out[:, el.start:el.stop:2] = raw.u[:, self._expand]
        out[:, el.start + 1:el.stop:2] = raw.f[:, self._expand]
        if self._shear:
            self._shear_columns(out)
        if self.dampers:
            dv = rows_times(raw.v, self._db) if not self._turning else np.repeat(
                np.einsum("kdi,ki->kd", self._drows(raw), raw.v), self._dcount, axis=1)
            ds = self.slices["dampers"]
            out[:, ds.start:ds.stop:2] = dv
            out[:, ds.start + 1:ds.stop:2] = dv * self._dc
        en = self.slices["energy"]
        out[:, en.start:en.start + 3] = raw.e[:, :3]
        error = raw.e[:, 0] - raw.e[:, 1] - raw.e[:, 2]
        if self.damped:
            out[:, en.start + 3] = raw.e[:, 3]
            error = error - raw.e[:, 3]
        out[:, en.stop - 1] = error

    def _shear_columns(self, out: np.ndarray) -> None:
        """The shear lines' columns from their springs' (written before): u_j = (2 / n) sum_i c_ij
        u_i (sum_i c_ij^2 = n / 2: the projection back), f_j = sum_i c_ij f_i."""
        el = self.slices["elements"].start
        first = self.slices["shear"].start
        for m, (_, springs, weights) in enumerate(self._shear):
            u = out[:, [el + 2 * c for c in springs]]
            f = out[:, [el + 2 * c + 1 for c in springs]]
            n = len(springs)
            for j in range(2):
                out[:, first + 4 * m + 2 * j] = (2.0 / n) * (u @ weights[j])
                out[:, first + 4 * m + 2 * j + 1] = f @ weights[j]

    def _drows(self, raw: Raw) -> np.ndarray:
        """(k, dampers, n) the dampers' rows at each row's configuration (exact kinematics)."""
        from rbhyst.model.kinematics import damper_rows

        return damper_rows(self.system, raw.d)

    def _viscous(self, raw: Raw) -> np.ndarray:
        """(k, n) the viscous force C v at each row: Rayleigh's and the dampers', whose rows turn
        with the body where the kinematics are exact."""
        if not self._turning:
            return rows_times(raw.v, self._ct)
        rows = self._drows(raw)
        rate = np.einsum("kdi,ki->kd", rows, raw.v)
        out = np.einsum("d,kd,kdi->ki", self._dcc, rate, rows)
        if self.system.rayleigh is not None:
            out += raw.v @ self.system.rayleigh.matrix.T
        return out

    def _table_space(self, raw: Raw, out: np.ndarray) -> np.ndarray:
        """``table`` for a body in space with exact kinematics (rbhyst.model.rotations): the kernels'
        state (u, psi; u', omega in the body's axes) to the ground's view, in the deck's axes:
        theta the rotation vector of the turn from the start (R R0^T), omega_s = R omega,
        alpha_s = R omega', the resultant's moment R M_b about G."""
        from rbhyst.model.rotations import body_loads, body_rows, gyroscopic, matrices, rotation_vectors

        n = len(self.coordinates)
        psi, omega = raw.d[:, 3:6], raw.v[:, 3:6]
        rm = matrices(psi)  # kernel axes
        f = raw.f * self.system.mult
        r_b = np.empty((len(raw.t), n))
        r_b[:, :3] = f @ self.system.bvec[:, :3]
        r_b[:, 3:] = np.einsum("ke,kei->ki", f, body_rows(self.system.bvec, self._axial, psi))
        at = body_loads(self.system.excitation.forces(raw.t), psi, n, self._axial) - r_b
        at[:, 3:] -= gyroscopic(self.system.mass, omega)
        if self.damped:
            at -= self._viscous(raw)
        at *= self._minv
        turn = lambda x: np.einsum("kij,kj->ki", rm, x)  # body axes -> ground (kernel axes)
        d = out[:, self.slices["d"]]
        d[:, :3] = raw.d[:, :3] - self.origin[:3]
        p = self._p
        d[:, 3:] = rotation_vectors((p @ rm @ p.T) @ self._r0.T)  # deck axes
        v = out[:, self.slices["v"]]
        v[:, :3] = raw.v[:, :3]
        v[:, 3:] = turn(omega) @ p.T
        r = out[:, self.slices["R"]]
        r[:, :3] = r_b[:, :3]
        r[:, 3:] = turn(r_b[:, 3:]) @ p.T
        a = out[:, self.slices["at"]]
        a[:, :3] = at[:, :3]
        a[:, 3:] = turn(at[:, 3:]) @ p.T
        self._rest(raw, out, a, omega=v[:, 3:])
        return out


def body_spectrum_columns(layout: Layout) -> list[tuple[tuple[str, str], int]]:
    """((location, direction), column) of every total acceleration of the body whose spectra a
    run gives: G and every point along each translation of q, x1 and x2 in the plane (the
    ground's come from its signals)."""
    from rbhyst.solve.located import CENTRE

    moving = [layout.coordinates[i] for i in translations(layout.coordinates)]
    out = [((CENTRE, f"x{c.axis}"), layout.index(c.column("at"))) for c in moving]
    for name, _ in layout.points:
        out += [((name, f"x{c.axis}"), layout.index(f"{name}_{c.column('at')}")) for c in moving]
    return out


@dataclass
class Extremes:
    """Signed extremes of every column and the first times they are reached, over every row seen."""

    names: tuple[str, ...]
    max: np.ndarray = None
    min: np.ndarray = None
    t_max: np.ndarray = None
    t_min: np.ndarray = None

    def __post_init__(self):
        m = len(self.names)
        self.max, self.min = np.full(m, -np.inf), np.full(m, np.inf)
        self.t_max, self.t_min = np.zeros(m), np.zeros(m)

    def peak(self, name: str) -> float:
        i = self.names.index(name)
        return float(max(abs(self.max[i]), abs(self.min[i])))

    def peaks(self) -> dict[str, float]:
        """max |value| of every column but time."""
        return {n: float(max(abs(hi), abs(lo))) for n, hi, lo in zip(self.names, self.max, self.min)
                if n != "time_s"}

    def as_dict(self) -> dict[str, dict[str, float]]:
        return {n: {"max": float(self.max[i]), "time_of_max_s": float(self.t_max[i]),
                    "min": float(self.min[i]), "time_of_min_s": float(self.t_min[i])}
                for i, n in enumerate(self.names) if n != "time_s"}


#: a time series is drawn from at most this many (min, max) pairs: more than a figure's pixels
PLOT_BUCKETS = 2000
#: curves drawn against each other (element loops) keep at most this many rows
PLOT_SAMPLES = 50_000


@dataclass
class PlotData:
    """What the plots need of a run of ``n_rows`` steps, whatever its length.

    ``lo``, ``hi``: the smallest and largest value of every column within each of up to
    PLOT_BUCKETS consecutive groups of steps (a line drawn through them keeps every peak);
    ``sample``: every ``stride``-th row, for curves of one column against another. Without
    ``drawn`` (a run that keeps only its reductions: a sweep's case) neither is kept and only
    the extremes and the last row are folded in (the buckets of a short run are a few rows each,
    and folding them took a sweep's case 0.5 ms, the extremes alone 0.1).
    """

    n_rows: int
    n_cols: int
    drawn: bool = True
    bucket: int = field(init=False)
    stride: int = field(init=False)
    lo: np.ndarray = field(init=False)
    hi: np.ndarray = field(init=False)
    t_lo: np.ndarray = field(init=False)
    t_hi: np.ndarray = field(init=False)
    final: np.ndarray | None = field(init=False, default=None)  # the last row
    _samples: list = field(init=False, default_factory=list)
    _seen: int = field(init=False, default=0)

    def __post_init__(self):
        self.bucket = max(1, -(-self.n_rows // PLOT_BUCKETS))
        self.stride = max(1, -(-self.n_rows // PLOT_SAMPLES))
        nb = -(-self.n_rows // self.bucket) if self.drawn else 0
        self.lo = np.full((nb, self.n_cols), np.inf)
        self.hi = np.full((nb, self.n_cols), -np.inf)
        self.t_lo = np.full(nb, np.inf)
        self.t_hi = np.full(nb, -np.inf)

    def update(self, table: np.ndarray, extremes: Extremes, folded: bool = False) -> None:
        """Fold a chunk of rows into the buckets and into ``extremes`` (one compiled pass).
        ``folded``: ``extremes`` has seen these rows already (the output rows of a step split
        into compute steps, whose every row was folded): a run that draws nothing keeps only
        the last row of them."""
        n = len(table)
        if n == 0:
            return
        if folded and not self.drawn:
            # (folding a subset of the rows folded gives the same extremes: a copy of the
            # strided rows and two passes over them saved)
            self._seen += n
            self.final = table[-1].copy()
            return
        # columns must be contiguous (the kernel runs down each); a block of rows of the run's
        # column-major table is, though not F-contiguous as a whole: no copy for it
        columns = table if table.strides[0] == table.itemsize else np.asfortranarray(table)
        if not self.drawn:
            fold_extremes(columns, extremes)
        else:
            kernel("reduce_rows")(columns, self._seen, self.bucket, extremes.max, extremes.t_max, extremes.min,
                                  extremes.t_min, self.lo, self.hi, self.t_lo, self.t_hi)
            first = (-self._seen) % self.stride
            # (a strided view would keep the whole chunk alive: copied; stride 1 keeps it anyway)
            self._samples.append(table if self.stride == 1 else table[first::self.stride].copy())
        self._seen += n
        self.final = table[-1].copy()

    @property
    def sample(self) -> np.ndarray:
        self._check_drawn()
        return np.vstack(self._samples) if self._samples else np.empty((0, self.n_cols))

    def series(self, col: int) -> tuple[np.ndarray, np.ndarray]:
        """(t, y) of a line through every bucket's extremes (the raw rows when there are few)."""
        self._check_drawn()
        if self.bucket == 1:
            return self.lo[:, 0], self.lo[:, col]
        t = np.column_stack([self.t_lo, self.t_hi]).ravel()
        y = np.column_stack([self.lo[:, col], self.hi[:, col]]).ravel()
        return t, y

    def _check_drawn(self) -> None:
        if not self.drawn:
            raise ValueError("this run kept only its reductions (no rows in memory nor in a folder): "
                             "it has nothing to draw")


def fold_extremes(columns: np.ndarray, extremes: Extremes) -> None:
    """Fold a chunk of rows (column 0 the time; columns contiguous) into ``extremes``: what
    PlotData's kernel gives them, a value's time the first at which the running extreme is
    reached (argmax: the first of ties)."""
    j = np.arange(columns.shape[1])
    for value, first, better, times in ((extremes.max, columns.argmax(axis=0), np.greater, extremes.t_max),
                                        (extremes.min, columns.argmin(axis=0), np.less, extremes.t_min)):
        x = columns[first, j]
        new = better(x, value)
        value[new] = x[new]
        times[new] = columns[first[new], 0]


def estimate_columns(layout: Layout) -> list[tuple[str, int, str]]:
    """(key, column, family) of every column whose error a run's estimate gives: G's motion and
    total acceleration, the mounts' resultant, each element's force and each point's motion.
    The key is the CSV column without its unit (``at1``, ``R3``, ``e3_f``, ``top_at2``); the
    family groups the columns whose scale is shared where one of them is at rest. Worked out
    once per layout (a run asks for them some five times)."""
    known = layout.__dict__.get("_estimate_columns")
    if known is None:
        known = layout.__dict__["_estimate_columns"] = _estimate_columns(layout)
    return list(known)


def _estimate_columns(layout: Layout) -> tuple[tuple[str, int, str], ...]:
    index = {name: i for i, name in enumerate(layout.names)}
    out = [(c.key(fam), index[c.column(fam)], fam) for fam in ("d", "at", "R") for c in layout.coordinates]
    moving = [layout.coordinates[i] for i in translations(layout.coordinates)]
    for name, _ in layout.points:
        out += [(f"{name}_{c.key(fam)}", index[f"{name}_{c.column(fam)}"], "p" + fam)
                for fam in ("d", "at") for c in moving]
    n_el = layout.system.n_output_elements
    out += [(f"e{k}_f", index[f"e{k}_f_N"], "ef") for k in range(1, n_el + 1)]
    return tuple(out)
