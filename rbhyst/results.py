"""Result of an analysis: time histories, peaks, energy balance, and their CSV / JSON writers."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import __version__

if TYPE_CHECKING:  # pragma: no cover
    from .model import System
    from .simulate import Settings

BASE_COLUMNS = (
    "time_s", "u1_m", "u2_m", "theta3_rad", "v1_m_s", "v2_m_s", "omega3_rad_s",
    "a1_m_s2", "a2_m_s2", "alpha3_rad_s2", "at1_m_s2", "at2_m_s2", "alphat3_rad_s2",
)
SUPPORT_COLUMNS = ("ag1_m_s2", "ag2_m_s2")
ENERGY_COLUMNS = ("E_input_J", "E_kinetic_J", "E_hysteretic_J", "E_error_J")

#: relative energy balance error above which a run is flagged (see README)
ENERGY_WARN = 0.01


@dataclass(frozen=True)
class Result:
    system: "System"
    settings: "Settings"
    time: np.ndarray  # (n,)
    d: np.ndarray  # (n, 3) u1, u2, theta3 relative to the support
    v: np.ndarray
    a: np.ndarray
    ag: np.ndarray | None  # (n, 2) support acceleration, None without support motion
    element_u: np.ndarray  # (n, n_el) deformation of each element, count expanded
    element_f: np.ndarray  # (n, n_el)
    energy: np.ndarray  # (n, 3) input, kinetic, hysteretic (cumulative)
    steps: int
    record_substeps: int = 1  # compute steps per dt to follow a finer record
    min_substep_level: int = 0  # every step split in 2**this for omega_0 h (structure-dependent methods)
    substeps: int = 0  # extra substeps taken where the stiffness needed them
    max_substep_level: int = 0
    max_omega_dt: float = 0.0
    steps_taken: int = 0  # steps actually taken, substeps included (0: not counted by the method)
    newton_iterations: int = 0  # newmark only
    wall_s: float = 0.0

    @property
    def total_acceleration(self) -> np.ndarray:
        """q'' + (ag1, ag2, 0): what an accelerometer on the body reads."""
        at = self.a.copy()
        if self.ag is not None:
            at[:, :2] += self.ag
        return at

    @property
    def energy_error(self) -> np.ndarray:
        e_in, e_kin, e_hyst = self.energy.T
        return e_in - e_kin - e_hyst

    @property
    def energy_balance(self) -> float:
        """max |E_error| / max |E_input| (0 for a scene with no input)."""
        scale = float(np.max(np.abs(self.energy[:, 0])))
        return float(np.max(np.abs(self.energy_error))) / scale if scale > 0 else 0.0

    def columns(self) -> tuple[list[str], np.ndarray]:
        """The time_history.csv table: names and an (n, k) array."""
        names = list(BASE_COLUMNS)
        parts = [self.time[:, None], self.d, self.v, self.a, self.total_acceleration]
        if self.ag is not None:
            names += SUPPORT_COLUMNS
            parts.append(self.ag)
        n_el = self.element_u.shape[1]
        eu = np.empty((len(self.time), 2 * n_el))
        eu[:, 0::2] = self.element_u
        eu[:, 1::2] = self.element_f
        for k in range(1, n_el + 1):
            names += [f"e{k}_u_m", f"e{k}_f_N"]
        parts.append(eu)
        names += ENERGY_COLUMNS
        parts += [self.energy, self.energy_error[:, None]]
        return names, np.hstack(parts)

    def summary(self) -> dict:
        names, table = self.columns()
        peaks = {n: float(np.max(np.abs(table[:, i]))) for i, n in enumerate(names) if n != "time_s"}
        body = self.system.body
        return {
            "rbhyst_version": __version__,
            "title": self.system.title,
            "body": {
                "area_m2": body.area,
                "mass_kg": float(self.system.mass[0]),
                "inertia_kgm2": float(self.system.mass[2]),
                "centroid_m": [float(c) for c in body.centroid],
                "vertices_m": body.vertices.tolist(),
            },
            "elements": [
                {"x_m": list(el.x), "angle_deg": el.angle_deg, "hysteresis": el.hysteresis,
                 "count": el.count, "k0_N_m": float(self.system.k0[el.row]),
                 "k_reversal_N_m": float(self.system.k_reversal[el.row])}
                for el in self.system.elements
            ],
            "analysis": {
                "integrator": self.settings.integrator,
                "dt_s": self.settings.dt,
                "steps": self.steps,
                "duration_s": self.steps * self.settings.dt,
                "output_every": self.settings.every,
                "record_substeps": self.record_substeps,
                "stiffness_substeps": self.substeps,
                "k0_substep_level": self.min_substep_level,
                "max_substep_level": self.max_substep_level,
                "max_omega_dt": self.max_omega_dt,
                "max_omega_dt_limit": self.settings.max_omega_dt,
                "steps_taken": self.steps_taken,
                "newton_iterations": self.newton_iterations,
                "wall_s": self.wall_s,
            },
            "energy": {
                "balance_error": self.energy_balance,
                "warn_above": ENERGY_WARN,
                "input_J": float(self.energy[-1, 0]),
                "hysteretic_J": float(self.energy[-1, 2]),
            },
            "peaks": peaks,
            "notes": list(self.system.notes),
        }


def write_csv(result: Result, path: Path) -> None:
    """time_history.csv, 10 significant digits (a row format applied to lists: faster than savetxt)."""
    names, table = result.columns()
    row = ",".join(["%.10g"] * table.shape[1])
    with open(path, "w") as fh:
        fh.write(",".join(names) + "\n")
        fh.write("\n".join([row % tuple(r) for r in table.tolist()]))
        fh.write("\n")


def write_summary(result: Result, path: Path) -> None:
    path.write_text(json.dumps(result.summary(), indent=2) + "\n")
