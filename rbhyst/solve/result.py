"""What a solve gives: the run's table (kept, or where it was streamed), its extremes, energy,
counters and spectra, and its summary (summary.json's content). The files are written by
:mod:`rbhyst.results.writers`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from rbhyst._version import __version__
from rbhyst.solve.history import BASE_COLUMNS, ENERGY_COLUMNS, SUPPORT_COLUMNS, Extremes, Layout, PlotData  # noqa: F401
from rbhyst.model.body import body_summary

if TYPE_CHECKING:  # pragma: no cover
    from rbhyst.model.system import System
    from rbhyst.solve.located import LocatedSpectra
    from rbhyst.model.settings import Settings

#: relative energy balance error above which a run is flagged (docs/explanation/integrators.md, "Energy balance")
ENERGY_WARN = 0.01


@dataclass
class RunStats:
    """What the time stepping took."""

    steps: int  # output steps of dt
    record_substeps: int = 1  # compute steps per dt to follow a finer excitation
    refine: int = 1  # ... times this, for the accuracy (rbhyst.solve.choose)
    min_substep_level: int = 0  # every step split in 2**this for omega_0 h (structure-dependent methods)
    substeps: int = 0  # extra substeps taken where the stiffness needed them
    max_substep_level: int = 0
    max_omega_dt: float = 0.0
    steps_taken: int = 0  # steps actually taken, substeps included (0: not counted by the method)
    newton_iterations: int = 0  # newmark only
    wall_s: float = 0.0  # the time stepping alone


@dataclass
class Result:
    """One analysis. ``table`` holds the rows time_history.csv has (every ``output.every``-th
    step) when the run was kept in memory; extremes, peaks and plots come from every step."""

    system: "System"
    settings: "Settings"
    columns: tuple[str, ...]
    table: np.ndarray | None
    extremes: Extremes
    plot: PlotData
    stats: RunStats
    layout: Layout | None = None
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    accuracy: dict | None = None
    csv_path: Path | None = None  # where the rows went when they were streamed
    solver: dict | None = None  # what an adaptive integration took (steps, reversals, ...)
    #: how rbhyst chose the compute step and kinematics of a deck that names no integrator
    #: (rbhyst.solve.choose): summary.json's analysis.chosen
    chosen: dict | None = None
    #: (n, 1 + k) time and the columns the error estimate compares (history.estimate_columns), at
    #: every ``compare_every``-th compute step
    compared: np.ndarray | None = None
    compare_every: int = 1
    spectra: "LocatedSpectra | None" = None  # output.spectra: of the ground, G and the points, over every step
    #: (result, out, plots=) -> folder: what :meth:`write` calls (set by the pipeline above)
    writer: Callable | None = field(default=None, repr=False, compare=False)
    deck: dict | None = None  # the deck as run (its keys as given, the run's overrides applied)
    #: when, by which rbhyst and command, from which files (rbhyst.files.provenance)
    provenance: dict | None = None
    #: the kinematic model and the error it carries (rbhyst.solve.kinematic), when checked
    kinematics: dict | None = None
    #: (kernel rows, 4) where elements have stops: each row's contacts begun, energy lost in its
    #: impacts (J, one element), largest contact force (N) and penetration (m) (plan.stop_record)
    stops: np.ndarray | None = None

    @property
    def q_sample(self) -> np.ndarray:
        """(n, 1 + len(q)) time and q (u1, u2, theta3) at the steps the estimate compares."""
        return self.compared[:, :1 + self.system.n]

    # ---------------------------------------------------------------- the table by name

    def column(self, name: str) -> np.ndarray:
        return self._rows()[:, self.columns.index(name)]

    def _rows(self) -> np.ndarray:
        if self.table is None:
            raise ValueError(f"this run's rows were streamed to {self.csv_path} and not kept in memory")
        return self.table

    def _group(self, key: str) -> np.ndarray:
        return self._rows()[:, self.layout.slices[key]]

    @property
    def time(self) -> np.ndarray:
        return self._rows()[:, 0]

    @property
    def d(self) -> np.ndarray:
        """(n, len(q)) u1, u2, theta3 relative to the support."""
        return self._group("d")

    @property
    def v(self) -> np.ndarray:
        return self._group("v")

    @property
    def a(self) -> np.ndarray:
        return self._group("a")

    @property
    def total_acceleration(self) -> np.ndarray:
        """q'' + (ag1, ag2, 0): what an accelerometer on the body reads."""
        return self._group("at")

    @property
    def ag(self) -> np.ndarray | None:
        return self._group("ag") if "ag" in self.layout.slices else None

    @property
    def element_u(self) -> np.ndarray:
        """(n, elements) deformation of each element, count expanded (CSV order)."""
        return self._group("elements")[:, 0::2]

    @property
    def element_f(self) -> np.ndarray:
        return self._group("elements")[:, 1::2]

    @property
    def energy(self) -> np.ndarray:
        """(n, 3) cumulative input, kinetic and hysteretic energy."""
        return self._group("energy")[:, :3]

    @property
    def energy_error(self) -> np.ndarray:
        return self._group("energy")[:, -1]

    @property
    def energy_balance(self) -> float:
        """max |E_error| / max |E_input| over every step (0 for a scene with no input)."""
        scale = self.extremes.peak("E_input_J")
        return self.extremes.peak("E_error_J") / scale if scale > 0 else 0.0

    # counters, as attributes of the result
    steps = property(lambda self: self.stats.steps)
    record_substeps = property(lambda self: self.stats.record_substeps)
    min_substep_level = property(lambda self: self.stats.min_substep_level)
    substeps = property(lambda self: self.stats.substeps)
    max_substep_level = property(lambda self: self.stats.max_substep_level)
    max_omega_dt = property(lambda self: self.stats.max_omega_dt)
    steps_taken = property(lambda self: self.stats.steps_taken)
    newton_iterations = property(lambda self: self.stats.newton_iterations)
    wall_s = property(lambda self: self.stats.wall_s)

    # ---------------------------------------------------------------- outputs

    def summary(self) -> dict:
        """summary.json as a dict."""
        system, s, st = self.system, self.settings, self.stats
        e = self.extremes
        return {
            "rbhyst_version": __version__,
            "title": system.title,
            "body": body_summary(system.body),
            "elements": self.elements_summary(),
            **({"dampers": [{"x_m": list(dp.x), **_line(dp), "c_N_s_m": dp.c, "count": dp.count}
                            for dp in system.dampers]} if system.dampers else {}),
            **({"rayleigh": system.rayleigh.summary()} if getattr(system, "rayleigh", None) is not None else {}),
            **({"static": self._static_summary()} if system.static is not None else {}),
            "modes": self._modes_summary(),
            **({"rang": self.rang_summary()} if self.compared is not None else {}),
            "analysis": {
                "integrator": s.integrator,
                "dt_s": s.dt,
                "steps": st.steps,
                "duration_s": st.steps * s.dt,
                "output_every": s.every,
                "record_substeps": st.record_substeps,
                **({"accuracy_substeps": st.refine} if st.refine > 1 else {}),
                "stiffness_substeps": st.substeps,
                "k0_substep_level": st.min_substep_level,
                "max_substep_level": st.max_substep_level,
                "max_omega_dt": st.max_omega_dt,
                "max_omega_dt_limit": s.max_omega_dt,
                "steps_taken": st.steps_taken,
                "newton_iterations": st.newton_iterations,
                "wall_s": st.wall_s,
                **({"rtol": s.rtol, "adaptive": self.solver} if self.solver is not None else {}),
                **({"chosen": self.chosen} if self.chosen is not None else {}),
            },
            "energy": self.energy_summary(),
            "accuracy": self.accuracy,
            **({"kinematics": self.kinematics} if self.kinematics is not None else {}),
            "peaks": e.peaks(),
            "extremes": e.as_dict(),
            "at_rest": self.at_rest(),
            "notes": list(self.notes),
            "warnings": list(self.warnings),
            **({"spectra": self.spectra.summary()} if self.spectra is not None else {}),
            **({"deck": self.deck} if self.deck is not None else {}),
            **({"provenance": self.provenance} if self.provenance is not None else {}),
        }

    def at_rest(self) -> list[str]:
        """The columns the run leaves at rest, to rounding (scales.at_rest_columns): their peaks
        are shown as 0."""
        from rbhyst.solve.scales import at_rest_columns

        return at_rest_columns(self)

    def energy_summary(self) -> dict:
        """summary.json's ``energy``: the balance's error and the work of the load, the elements
        and the dampers at the end."""
        return {
            "balance_error": self.energy_balance,
            "warn_above": ENERGY_WARN,
            "input_J": float(self._final("E_input_J")),
            "hysteretic_J": float(self._final("E_hysteretic_J")),
            **({"viscous_J": float(self._final("E_viscous_J"))} if "E_viscous_J" in self.columns else {}),
            **({"impact_J": self.impact_energy,
                "impact_note": "lost in the stops' impacts; part of hysteretic_J (the work of the mounts' forces), "
                               "so input = kinetic + hysteretic + viscous + error"} if self.stops is not None else {}),
        }

    @property
    def impact_energy(self) -> float:
        """The energy every stop's impacts lost over the run (J; 0 without stops)."""
        if self.stops is None:
            return 0.0
        return float(np.sum(self.system.mult * self.stops[:, 1]))

    def elements_summary(self) -> list[dict]:
        """Each [[elements]] entry, then each direction of each [[isolators]] entry: place, set,
        stiffnesses, for an isolator's the isolator (1-based) and the role (axial, shear1,
        shear2; in the plane axial, shear), and where it has a stroke, how much of it the run used
        (peak deformation over every step / its limit, and when)."""
        system, e = self.system, self.extremes
        out, k = [], 1
        for el in system.elements:
            entry = {"x_m": list(el.x), **_line(el), "hysteresis": el.hysteresis,
                     "count": el.count, "k0_N_m": float(system.k0[el.row]),
                     "k_reversal_N_m": float(system.k_reversal[el.row])}
            if getattr(el, "isolator", None) is not None:
                entry.update(isolator=el.isolator, role=el.role)
            if el.stroke is not None:
                entry["stroke"] = stroke_use(e, f"e{k}_u_m", el.stroke)
            if el.stop is not None:
                entry["stop"] = self._stop_summary(el)
            out.append(entry)
            k += el.count
        return out

    def _stop_summary(self, el) -> dict:
        """An element's stop: its law and, for each of its ``count`` elements alike, the contacts
        begun, the largest contact force and penetration, the energy its impacts lost."""
        lo, hi, k, r = el.stop
        # (a contact's stop has one side: the other is null, JSON having no infinity)
        out = {"gap_m": [lo + 0.0 if np.isfinite(lo) else None, hi if np.isfinite(hi) else None],
               "stiffness_N_m": k, "restitution": r,
               "law": "Walton-Braun: loading K d, unloading K/e^2 from the peak"}
        if self.stops is not None:
            n, lost, force, depth = (float(v) for v in self.stops[el.row])
            out.update(impacts=round(n), peak_force_N=force, peak_penetration_m=depth, impact_J=lost)
        return out

    def _static_summary(self) -> dict:
        st = self.system.static
        from rbhyst.solve.stops import element_forces

        u = self.system.expand(st.st[None, :, 0])[0]
        f = self.system.expand(element_forces(st.st)[None] + 0.0)[0]
        q = self.system.to_deck(st.q) if hasattr(self.system, "to_deck") else st.q
        return {**{c.column("d"): float(x) for c, x in zip(self.system.coordinates, q)},
                "elements": [{"u_m": float(a), "f_N": float(b)} for a, b in zip(u, f)],
                "out_of_balance": st.residual, "iterations": st.iterations,
                "note": "displacements in time_history.csv are measured from here; element deformations are total"}

    def _modes_summary(self) -> dict:
        """The undamped modes of the initial system and, at rest under gravity, of its tangent
        (rbhyst.solve.modes); at_rest only where the run found the static equilibrium."""
        from rbhyst.solve.modes import modes_summary

        system = self.system
        if system.weight is not None and system.static is None:  # (not a run's: no equilibrium to take)
            import dataclasses

            system = dataclasses.replace(system, weight=None)
        return modes_summary(system)

    def rang_summary(self) -> dict:
        """The frequency each coordinate rang at after the excitation ended (rbhyst.solve.ringing),
        from the response the error estimate compares."""
        from rbhyst.solve.ringing import ringing

        coords = self.system.coordinates
        ends = [signal.end for signal in self.system.excitation.signals.values()]
        free_from = None if None in ends else max(ends, default=0.0)
        n = len(coords)
        m = np.asarray(self.system.mass, dtype=float)
        m = np.diag(m) if m.ndim == 2 else m
        mt = max((m[i] for i, c in enumerate(coords) if not c.rotation), default=1.0)
        lengths = [float(np.sqrt(m[i] / mt)) if c.rotation else 1.0 for i, c in enumerate(coords)]
        return ringing(self.compared[:, 0], self.compared[:, 1:1 + n], [c.key("d") for c in coords], free_from,
                       lengths)

    def _final(self, name: str) -> float:
        return self.plot.final[self.columns.index(name)]

    def write(self, out, plots: bool = True):
        """Write the files ``rbhyst run`` writes (time_history.csv, summary.json, PNGs) into ``out``,
        with the writer the pipeline that made this result gave it (rbhyst.api.write)."""
        if self.writer is None:
            raise TypeError("this Result was made by rbhyst.solve directly, without a writer: "
                            "write it with rbhyst.api.write(result, out)")
        return self.writer(self, out, plots=plots)

    def to_pandas(self):
        """A DataFrame with exactly time_history.csv's columns (imports pandas)."""
        import pandas as pd

        return pd.DataFrame(self._rows(), columns=list(self.columns))


def _line(entry) -> dict:
    """An element's or damper's line of action in summary.json: ``angle_deg`` in the plane,
    ``direction`` (unit) in space."""
    direction = getattr(entry, "direction", None)
    return {"angle_deg": entry.angle_deg} if direction is None else {"direction": list(direction)}


def stroke_use(extremes: Extremes, column: str, limits: tuple[float, float]) -> dict:
    """How much of its stroke an element used: peak deformation (signed), utilization = peak /
    the limit on its side, and the first time it was reached."""
    i = extremes.names.index(column)
    lo, hi = limits
    up, down = extremes.max[i] / hi, extremes.min[i] / lo
    if up >= down:
        peak, t, use = extremes.max[i], extremes.t_max[i], up
    else:
        peak, t, use = extremes.min[i], extremes.t_min[i], down
    return {"limits_m": [lo, hi], "peak_deformation_m": float(peak), "utilization": float(use),
            "time_of_peak_s": float(t)}
