"""Required response spectra (RRS): ICC-ES AC156 built in, any other from a CSV file.

An RRS is a curve of spectral acceleration (the maximax absolute acceleration of a linear
oscillator, as rbhyst.response computes it) against oscillator frequency at one damping ratio,
with the frequency range over which a test response spectrum (TRS) must lie within a band of it
(0.9 to 1.3 times the RRS for AC156). Between breakpoints it is a straight line on log-log axes.

AC156 (ICC-ES AC156, Acceptance Criteria for Seismic Certification by Shake-Table Testing of
Nonstructural Components, the form that goes with ASCE 7-05 to 7-16), 5 % damping:

- horizontal: A_FLX-H = S_DS (1 + 2 z/h), at most 1.6 S_DS; A_RIG-H = 0.4 S_DS (1 + 2 z/h),
  at most 1.2 S_DS;
- vertical: A_FLX-V = 0.67 S_DS, A_RIG-V = 0.27 S_DS;
- shape: A_FLX flat from 1.3 to 8.3 Hz, a straight line on log-log axes down to A_RIG at
  33.3 Hz, A_RIG above; below 1.3 Hz the straight log-log line through A_FLX / 10 at 0.1 Hz
  (the standard's figure, read as an open implementation reads it; it lies outside the range
  the TRS is held to, 1.3 to 33.3 Hz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.files.curves import Curve, read_curve
from rbhyst.files.units import label_unit

G = 9.80665
ACCEL_TO_SI = {"g": G, "m/s2": 1.0, "cm/s2": 0.01, "mg": G / 1000.0}

#: AC156's breakpoints (Hz) and the range over which the TRS must envelope the RRS
AC156_F = (0.1, 1.3, 8.3, 33.3)
AC156_RANGE = (1.3, 33.3)
#: the TRS must lie within these multiples of the RRS at every checked frequency (AC156)
AC156_BAND = (0.9, 1.3)
AC156_DAMPING = 0.05
#: AC156's test motion: total duration and strong-motion part (s)
AC156_DURATION, AC156_STRONG = 30.0, 20.0
STANDARDS = ("ac156",)


@dataclass(frozen=True)
class RRS:
    """A required response spectrum: ``sa`` (m/s2) at ``frequency_hz`` (ascending), log-log
    between them and flat beyond both ends; the TRS is held to ``band`` times it over
    ``check_range`` (Hz)."""

    name: str
    damping: float
    frequency_hz: np.ndarray
    sa: np.ndarray
    check_range: tuple[float, float]
    band: tuple[float, float] = AC156_BAND
    source: str = ""

    def __call__(self, f) -> np.ndarray:
        """sa (m/s2) at frequencies f (Hz)."""
        lf = np.log(np.clip(np.asarray(f, float), self.frequency_hz[0], self.frequency_hz[-1]))
        return np.exp(np.interp(lf, np.log(self.frequency_hz), np.log(self.sa)))

    @property
    def sa_g(self) -> np.ndarray:
        return self.sa / G

    def describe(self) -> dict:
        return {"name": self.name, "damping": self.damping, "check_range_hz": list(self.check_range),
                "band": list(self.band), "frequency_hz": [float(f) for f in self.frequency_hz],
                "sa_g": [float(a) for a in self.sa_g], "source": self.source}


def ac156_levels(sds: float, z_over_h: float) -> dict[str, float]:
    """A_FLX-H, A_RIG-H, A_FLX-V, A_RIG-V in g."""
    amp = 1.0 + 2.0 * z_over_h
    return {"AFLX-H": min(sds * amp, 1.6 * sds), "ARIG-H": min(0.4 * sds * amp, 1.2 * sds),
            "AFLX-V": 0.67 * sds, "ARIG-V": 0.27 * sds}


def ac156_problems(sds, z_over_h, sds_key: str = "--sds", z_key: str = "--z-over-h") -> list[str]:
    problems = []
    if sds is None:
        problems.append(f"{sds_key}: required with the AC156 spectrum (S_DS, the design spectral acceleration "
                        "at short periods, in g)")
    elif not (sds > 0 and math.isfinite(sds)):
        problems.append(f"{sds_key}: {sds:g} must be a positive number of g")
    if z_over_h is None:
        problems.append(f"{z_key}: required with the AC156 spectrum (z/h, the attachment height over the roof "
                        "height, 0 at grade to 1 at the roof)")
    elif not 0.0 <= z_over_h <= 1.0:
        problems.append(f"{z_key}: {z_over_h:g} must be from 0 (grade) to 1 (roof): z is at most h")
    return problems


def ac156(sds: float, z_over_h: float) -> dict[str, RRS]:
    """AC156's horizontal (x1) and vertical (x2) RRS for S_DS (g) at z/h."""
    problems = ac156_problems(sds, z_over_h)
    if problems:
        raise InputError(problems)
    lv = ac156_levels(sds, z_over_h)
    out = {}
    for axis, (flx, rig), what in (("x1", (lv["AFLX-H"], lv["ARIG-H"]), "horizontal"),
                                    ("x2", (lv["AFLX-V"], lv["ARIG-V"]), "vertical")):
        sa_g = np.array([flx / 10.0, flx, flx, rig])
        out[axis] = RRS(f"AC156 {what}, SDS = {sds:g} g, z/h = {z_over_h:g}", AC156_DAMPING,
                        np.array(AC156_F), sa_g * G, AC156_RANGE, AC156_BAND,
                        "ICC-ES AC156 (with ASCE 7-05 to 7-16)")
    return out


def sixth_octave(f_lo: float, f_hi: float) -> np.ndarray:
    """1/6-octave frequencies from f_lo up to f_hi, f_hi itself included."""
    n = int(math.floor(6.0 * math.log2(f_hi / f_lo) + 1e-9))
    f = f_lo * 2.0 ** (np.arange(n + 1) / 6.0)
    return f if f[-1] >= f_hi * (1 - 1e-9) else np.append(f, f_hi)


# ---------------------------------------------------------------- from files


def frequency_label_problem(path: Path, curve: Curve) -> str | None:
    """A first column whose label declares a unit other than Hz."""
    if curve.header_line is None or len(curve.labels) != 2:
        return None
    label = curve.labels[0]
    token, _ = label_unit(label)
    tail = label.strip().lower()
    if tail.endswith(("_hz", "[hz]", "(hz)")) or tail in ("f", "freq", "frequency"):
        return None
    if token is not None:
        return f"{path}:{curve.header_line}: the first column {label!r} must be the frequency in Hz (frequency_hz)"
    return None


def read_rrs(path: Path, damping: float | None, name: str = "", damping_key: str = "--rrs-damping") -> RRS:
    """An RRS from a CSV: ``frequency_hz`` and a value column whose header states its unit
    (``sa_g``, ``sa_m_s2``, ``sa [g]``); ``damping`` is the ratio it is drawn for (required:
    never guessed). The TRS is held to 0.9-1.3 times it over the file's frequency range."""
    path = Path(path)
    problems = []
    if damping is None:
        problems.append(f"{damping_key}: required with an RRS file: the damping ratio it is drawn for (0.05 for 5 %)")
    elif not 0.0 <= damping < 1.0:
        problems.append(f"{damping_key}: {damping:g} must be a ratio from 0 to below 1 (0.05 for 5 %)")
    curve = read_curve(path, "an RRS")
    problem = frequency_label_problem(path, curve)
    if problem:
        problems.append(problem)
    unit = None
    if curve.header_line is not None and len(curve.labels) == 2:
        token, unit = label_unit(curve.labels[1])
        if unit is not None and unit.name not in ACCEL_TO_SI:
            problems.append(f"{path}:{curve.header_line}: the value column {curve.labels[1]!r} is in {unit.name}; "
                            f"an RRS is an acceleration: {', '.join(ACCEL_TO_SI)}")
            unit = None
        elif unit is None and token is not None:
            problems.append(f"{path}:{curve.header_line}: the value column {curve.labels[1]!r}: {token!r} is not "
                            f"an acceleration unit rbhyst knows ({', '.join(ACCEL_TO_SI)})")
    if unit is None and not problems:
        where = f"{path}:{curve.header_line}" if curve.header_line is not None else f"{path}:1"
        problems.append(f"{where}: the header must state the value's unit, as record files do: "
                        "frequency_hz,sa_g (or sa_m_s2, sa [g], ...)")
    if problems:
        raise InputError(problems)
    return RRS(name or path.stem, float(damping), curve.x, curve.y * ACCEL_TO_SI[unit.name],
               (float(curve.x[0]), float(curve.x[-1])), AC156_BAND, str(path.name))


def requested_rrs(rrs: str | None, rrs_x2: str | None, damping: float | None, sds: float | None,
                  z_over_h: float | None, base: Path, keys: dict[str, str]) -> tuple[dict[str, RRS], str | None]:
    """The RRS per axis a command asks for, and the standard's name (None for files): ``rrs`` a
    standard's name or the x1 (horizontal) RRS file, ``rrs_x2`` the vertical one's file.
    ``keys`` names the options (or deck keys) in messages: rrs, rrs_x2, damping, sds, z_over_h."""
    if rrs is None:
        raise InputError(f"{keys['rrs']}: required: {', '.join(STANDARDS)} or an RRS file (frequency_hz,sa_g)")
    if rrs.lower() in STANDARDS:
        problems = ac156_problems(sds, z_over_h, keys["sds"], keys["z_over_h"])
        problems += [f"{keys[k]}: not with {keys['rrs']} {rrs}: the standard gives it" for k, v in
                     (("rrs_x2", rrs_x2), ("damping", damping)) if v is not None]
        if problems:
            raise InputError(problems)
        return ac156(sds, z_over_h), rrs.lower()
    problems = [f"{keys[k]}: only with {keys['rrs']} {', '.join(STANDARDS)}" for k, v in
                (("sds", sds), ("z_over_h", z_over_h)) if v is not None]
    out = {}
    for axis, name in (("x1", rrs), ("x2", rrs_x2)):
        if name is None:
            continue
        path = Path(name) if Path(name).is_absolute() else base / name
        try:
            out[axis] = read_rrs(path, damping, f"{Path(name).stem} ({axis})", keys["damping"])
        except InputError as err:
            problems += [p for p in err.problems if p not in problems]
    if problems:
        raise InputError(problems)
    return out, None
