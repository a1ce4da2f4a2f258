"""Required response spectra (RRS): ICC-ES AC156 and IEEE Std 693 built in, any other from a
CSV file.

An RRS is a curve of spectral acceleration (the maximax absolute acceleration of a linear
oscillator, as rbhyst.response computes it) against oscillator frequency at one damping ratio,
with the frequency range over which a test response spectrum (TRS) must lie within a band of it
(0.9 to 1.3 times the RRS for AC156) and, for the standards, the least peak acceleration of the
record (a multiple of the RRS at the top of that range). Between breakpoints it is a straight
line on log-log axes, unless the standard gives it by formulas (IEEE 693), which it then follows
exactly.

AC156 (ICC-ES AC156, Acceptance Criteria for Seismic Certification by Shake-Table Testing of
Nonstructural Components, the form that goes with ASCE 7-05 to 7-16), 5 % damping:

- horizontal: A_FLX-H = S_DS (1 + 2 z/h), at most 1.6 S_DS; A_RIG-H = 0.4 S_DS (1 + 2 z/h),
  at most 1.2 S_DS;
- vertical: A_FLX-V = 0.67 S_DS, A_RIG-V = 0.27 S_DS;
- shape: A_FLX flat from 1.3 to 8.3 Hz, a straight line on log-log axes down to A_RIG at
  33.3 Hz, A_RIG above; below 1.3 Hz the straight log-log line through A_FLX / 10 at 0.1 Hz
  (the standard's figure, read as an open implementation reads it; it lies outside the range
  the TRS is held to, 1.3 to 33.3 Hz);
- the record's peak acceleration at least 0.9 A_RIG (the TRS at 33.3 Hz and above).

IEEE 693 (IEEE Std 693-2005, Recommended Practice for Seismic Design of Substations, Annex A:
Figure A.1, the high performance level's required response spectrum, and Figure A.2, the
moderate level's, half of it at every frequency and damping; the 2018 edition keeps the shape),
in g, f in Hz, beta = (3.21 - 0.68 ln(100 zeta)) / 2.1156 (Newmark and Hall's median amplification
3.21 - 0.68 ln(zeta %), normalised at 5 %: beta(0.05) = 0.99999), for the high level:

- Sa = 2.288 beta f for f < 1.1 Hz;
- Sa = 2.5 beta from 1.1 to 8 Hz;
- Sa = (26.4 beta - 10.56) / f - 0.8 beta + 1.32 from 8 to 33 Hz (continuous at 8 Hz, 2.5 beta,
  and at 33 Hz, 1.0, for every beta);
- Sa = 1.0 (the ZPA) above 33 Hz;

the moderate level half of it (1.144 beta f, 1.25 beta, (13.2 beta - 5.28) / f - 0.4 beta + 0.66,
0.5 g); the vertical (x2) 80 % of the horizontal (x1) at every frequency. At 1.1 Hz the first
line gives 2.517 beta, 0.7 % above the plateau: a step the standard's formulas have (2.288 is
not 2.5 / 1.1), kept. Its test motion: the TRS computed at 5 % damping must envelop the RRS, the
range including the lower corner, 1.1 Hz (read here as 1.1 to 33 Hz), and 20 s of strong
motion; the upper tolerance (1.3 times the RRS here) and the least peak acceleration (the ZPA
itself here) are rbhyst's defaults where the text was not at hand.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

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
#: AC156: the record's peak acceleration must be at least this multiple of A_RIG
AC156_ZPA_RATIO = 0.9

#: IEEE 693's breakpoints (Hz): the lower corner, the end of the plateau, the ZPA's start
IEEE693_F = (1.1, 8.0, 33.0)
#: the TRS is checked over this range (the lower corner, 1.1 Hz, included; the ZPA from 33 Hz)
IEEE693_RANGE = (1.1, 33.0)
#: "envelop": at least the RRS; at most 1.3 times it, rbhyst's default (as AC156's upper limit)
IEEE693_BAND = (1.0, 1.3)
#: the damping the TRS is computed at for matching (the RRS follows beta at any other)
IEEE693_DAMPING = 0.05
#: the damping ratios beta is used over (Newmark and Hall's amplification factors' range)
IEEE693_DAMPING_RANGE = (0.005, 0.2)
#: the horizontal ZPA (g) of each level's performance level spectrum (Figures A.1, A.2)
IEEE693_LEVELS = {"high": 1.0, "moderate": 0.5}
#: the vertical spectrum is this fraction of the horizontal
IEEE693_VERTICAL = 0.8
#: the record's peak acceleration must be at least this multiple of the ZPA (rbhyst's default)
IEEE693_ZPA_RATIO = 1.0
#: IEEE 693's test motion: strong-motion part (s), within a motion of ramps of 5 s
IEEE693_DURATION, IEEE693_STRONG = 30.0, 20.0
STANDARDS = ("ac156", "ieee693")


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
    #: the record's peak acceleration must be at least this multiple of the RRS at the top of
    #: ``check_range`` (None: not checked, as for a file's RRS)
    zpa_ratio: float | None = None
    #: the least strong motion (s, rbhyst.analyses.qualification.strong_motion's bracketed
    #: duration) a record must hold; None: not checked
    strong_min_s: float | None = None
    #: sa (m/s2) at f (Hz) where a standard gives the curve by formulas (``frequency_hz`` and
    #: ``sa`` then tabulate it at its breakpoints); None: log-log between the breakpoints
    shape: Callable | None = None
    #: the formulas ``shape`` follows, as text
    formula: str = ""

    def __call__(self, f) -> np.ndarray:
        """sa (m/s2) at frequencies f (Hz)."""
        if self.shape is not None:
            return self.shape(np.asarray(f, float))
        lf = np.log(np.clip(np.asarray(f, float), self.frequency_hz[0], self.frequency_hz[-1]))
        return np.exp(np.interp(lf, np.log(self.frequency_hz), np.log(self.sa)))

    @property
    def peak_min(self) -> float | None:
        """The least peak acceleration (m/s2) a record must reach, None when not checked."""
        return None if self.zpa_ratio is None else self.zpa_ratio * float(self(self.check_range[1]))

    @property
    def sa_g(self) -> np.ndarray:
        return self.sa / G

    def describe(self) -> dict:
        """The RRS as checked: its points, log-log between them. A standard's formulas (``shape``)
        are tabulated on the fine grid over its breakpoints' range and at them (log-log between
        the points reads them within 1e-5), their text and breakpoints beside."""
        if self.shape is None:
            f, extra = self.frequency_hz, {}
        else:
            # the breakpoints, and a point just below each, so that its kinks and steps (IEEE 693's
            # at 1.1 Hz) read as they are
            inner = self.frequency_hz[1:-1]
            f = np.unique(np.concatenate([fine_grid(float(self.frequency_hz[0]), float(self.frequency_hz[-1])),
                                          inner, inner * (1.0 - 1e-9)]))
            extra = {"formula": self.formula, "breakpoints_hz": [float(x) for x in self.frequency_hz],
                     "breakpoints_sa_g": [float(a) for a in self.sa_g]}
        return {"name": self.name, "damping": self.damping, "check_range_hz": list(self.check_range),
                "band": list(self.band), "frequency_hz": [float(x) for x in f],
                "sa_g": [float(a) for a in self(f) / G], **extra, "source": self.source,
                "peak_min_ratio": self.zpa_ratio, "strong_motion_min_s": self.strong_min_s,
                "peak_min_g": None if self.peak_min is None else self.peak_min / G}


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
                        "ICC-ES AC156 (with ASCE 7-05 to 7-16)", AC156_ZPA_RATIO, AC156_STRONG)
    return out


def ieee693_beta(damping: float) -> float:
    """IEEE 693's damping factor: (3.21 - 0.68 ln(100 zeta)) / 2.1156 (0.99999 at 5 %)."""
    return (3.21 - 0.68 * math.log(100.0 * damping)) / 2.1156


def ieee693_sa_g(f, level: str, damping: float = IEEE693_DAMPING) -> np.ndarray:
    """IEEE 693's horizontal performance level spectrum (g) of ``level`` at frequencies f (Hz)."""
    f = np.asarray(f, float)
    b = ieee693_beta(damping)
    high = np.where(f < 1.1, 2.288 * b * f,
                    np.where(f <= 8.0, 2.5 * b,
                             np.where(f <= 33.0, (26.4 * b - 10.56) / np.maximum(f, 1e-300) - 0.8 * b + 1.32, 1.0)))
    return IEEE693_LEVELS[level] * high


def ieee693_problems(level, damping, level_key: str = "--level", damping_key: str = "--rrs-damping") -> list[str]:
    problems = []
    if level is None:
        problems.append(f"{level_key}: required with the IEEE 693 spectrum: {' or '.join(IEEE693_LEVELS)} "
                        "(its performance level)")
    elif str(level).lower() not in IEEE693_LEVELS:
        problems.append(f"{level_key}: {level!r}: {' or '.join(IEEE693_LEVELS)}")
    lo, hi = IEEE693_DAMPING_RANGE
    if damping is not None and not lo <= damping <= hi:
        problems.append(f"{damping_key}: {damping:g}: IEEE 693's damping factor is used from {lo:g} to {hi:g} "
                        f"({IEEE693_DAMPING:g} by default, the damping it is matched at)")
    return problems


def ieee693_formula(level: str, damping: float, factor: float = 1.0) -> str:
    """IEEE 693's spectrum as text, with its beta and level factor."""
    scale = IEEE693_LEVELS[level] * factor
    return (f"{scale:g} x [2.288 beta f below 1.1 Hz; 2.5 beta from 1.1 to 8 Hz; (26.4 beta - 10.56) / f - 0.8 beta "
            f"+ 1.32 from 8 to 33 Hz; 1.0 above 33 Hz] g, f in Hz, beta = (3.21 - 0.68 ln(100 zeta)) / 2.1156 = "
            f"{ieee693_beta(damping):.4g} at zeta = {damping:g}")


def ieee693(level: str, damping: float | None = None) -> dict[str, RRS]:
    """IEEE 693's horizontal (x1) and vertical (x2, 80 % of it) RRS of the ``level``
    (high or moderate) performance level spectrum, drawn at ``damping`` (5 % by default)."""
    problems = ieee693_problems(level, damping)
    if problems:
        raise InputError(problems)
    level = level.lower()
    damping = IEEE693_DAMPING if damping is None else float(damping)
    f = np.array((0.1,) + IEEE693_F + (100.0,))
    out = {}
    for axis, factor, what in (("x1", 1.0, "horizontal"), ("x2", IEEE693_VERTICAL, "vertical")):
        def shape(x, factor=factor):
            return factor * G * ieee693_sa_g(x, level, damping)
        out[axis] = RRS(f"IEEE 693 {level} performance level, {what}", damping, f, shape(f), IEEE693_RANGE,
                        IEEE693_BAND, f"IEEE Std 693-2005, Figure A.{1 if level == 'high' else 2}"
                        + ("" if axis == "x1" else ", vertical 80 %"), IEEE693_ZPA_RATIO, IEEE693_STRONG, shape,
                        ieee693_formula(level, damping, factor))
    return out


def octave_points(f_lo: float, f_hi: float, per_octave: int) -> np.ndarray:
    """``per_octave`` frequencies an octave from f_lo up to f_hi, f_hi itself included."""
    n = int(math.floor(per_octave * math.log2(f_hi / f_lo) + 1e-9))
    f = f_lo * 2.0 ** (np.arange(n + 1) / per_octave)
    return f if f[-1] >= f_hi * (1 - 1e-9) else np.append(f, f_hi)


def sixth_octave(f_lo: float, f_hi: float) -> np.ndarray:
    """1/6-octave frequencies from f_lo up to f_hi, f_hi itself included: the standard's points."""
    return octave_points(f_lo, f_hi, 6)


#: the fine grid's points per octave: about 160 per decade, above the 100 per decade at least
#: that NRC SRP 3.7.1 (Rev. 4, II.1.B) asks of the frequencies a spectrum is computed at; a
#: multiple of 6, so that it holds the 1/6-octave points
FINE_PER_OCTAVE = 48


def fine_grid(f_lo: float, f_hi: float) -> np.ndarray:
    """1/48-octave frequencies from f_lo up to f_hi, f_hi included: every 1/6-octave point among them."""
    return octave_points(f_lo, f_hi, FINE_PER_OCTAVE)


def standard_points(fine: np.ndarray, check_range: tuple[float, float]) -> np.ndarray:
    """Which of the fine grid's frequencies are the 1/6-octave points (a mask)."""
    six = sixth_octave(*check_range)
    return np.isin(np.arange(len(fine)), np.searchsorted(fine, six * (1 - 1e-12)))


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


def acceleration_column(path: Path, curve: Curve, what: str, example: str, checked: bool = False):
    """(unit, problems) of a spectrum file of ``frequency_hz`` and an acceleration column whose header
    states its unit (an RRS, an SRS specification): the unit is None where there are problems.
    ``checked``: other problems were found before (no line then asks for the header's unit)."""
    problems = [p for p in [frequency_label_problem(path, curve)] if p]
    unit = None
    if curve.header_line is not None and len(curve.labels) == 2:
        token, unit = label_unit(curve.labels[1])
        if unit is not None and unit.name not in ACCEL_TO_SI:
            problems.append(f"{path}:{curve.header_line}: the value column {curve.labels[1]!r} is in {unit.name}; "
                            f"{what} is an acceleration: {', '.join(ACCEL_TO_SI)}")
            unit = None
        elif unit is None and token is not None:
            problems.append(f"{path}:{curve.header_line}: the value column {curve.labels[1]!r}: {token!r} is not "
                            f"an acceleration unit rbhyst knows ({', '.join(ACCEL_TO_SI)})")
    if unit is None and not problems and not checked:
        where = f"{path}:{curve.header_line}" if curve.header_line is not None else f"{path}:1"
        problems.append(f"{where}: the header must state the value's unit, as record files do: {example}")
    return (unit if not problems else None), problems


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
    unit, more = acceleration_column(path, curve, "an RRS", "frequency_hz,sa_g (or sa_m_s2, sa [g], ...)",
                                     checked=bool(problems))
    problems += more
    if problems:
        raise InputError(problems)
    return RRS(name or path.stem, float(damping), curve.x, curve.y * ACCEL_TO_SI[unit.name],
               (float(curve.x[0]), float(curve.x[-1])), AC156_BAND, str(path.name))


#: the axes of a deck in the plane (x1 horizontal, x2 vertical) and in space (x1, x2
#: horizontal, x3 vertical): what each is
PLANE_AXES = {"x1": "horizontal", "x2": "vertical"}
SPACE_AXES = {"x1": "horizontal", "x2": "horizontal", "x3": "vertical"}


def in_space(rrs: dict[str, RRS]) -> dict[str, RRS]:
    """A standard's RRS for a deck in space: its horizontal (x1) for x1 and x2, its vertical
    (x2 in the plane) for x3."""
    return {"x1": rrs["x1"], "x2": rrs["x1"], "x3": rrs["x2"]}


def requested_rrs(rrs: str | None, rrs_x2: str | None, damping: float | None, sds: float | None,
                  z_over_h: float | None, base: Path, keys: dict[str, str],
                  level: str | None = None, rrs_x3: str | None = None,
                  space: bool = False) -> tuple[dict[str, RRS], str | None]:
    """The RRS per axis a command asks for, and the standard's name (None for files): ``rrs`` a
    standard's name or the x1 (horizontal) RRS file, ``rrs_x2`` the vertical one's file.
    ``keys`` names the options (or deck keys) in messages: rrs, rrs_x2, rrs_x3, damping, sds,
    z_over_h, level (``level``: IEEE 693's, high or moderate).

    ``space``: for a deck in space, whose x1 and x2 are horizontal and x3 vertical: a standard
    gives its horizontal RRS to x1 and x2 and its vertical to x3; a file ``rrs`` is the RRS of
    x1 and of x2 (``rrs_x2``, when given, of x2 alone), ``rrs_x3`` the vertical's."""
    level_key = keys.get("level", "--level")
    x3_key = keys.get("rrs_x3", "--rrs-x3")
    if rrs_x3 is not None and not space:
        x2_key = "--rrs-x2" if x3_key.startswith("--") else keys["rrs_x2"]  # (as the user gave x3)
        raise InputError(f"{x3_key}: the deck is in the plane (2-D), whose vertical is x2: "
                         f"{x2_key} gives its RRS (x3 is the vertical of a deck in space)")
    if rrs is None:
        raise InputError(f"{keys['rrs']}: required: {', '.join(STANDARDS)} or an RRS file (frequency_hz,sa_g)")
    standard = rrs.lower()
    if standard == "ac156":
        problems = ac156_problems(sds, z_over_h, keys["sds"], keys["z_over_h"])
        problems += [f"{keys[k]}: not with {keys['rrs']} {rrs}: the standard gives it" for k, v in
                     (("rrs_x2", rrs_x2), ("damping", damping)) if v is not None]
        problems += [f"{x3_key}: not with {keys['rrs']} {rrs}: the standard gives it"] if rrs_x3 is not None else []
        problems += [f"{level_key}: only with {keys['rrs']} ieee693"] if level is not None else []
        if problems:
            raise InputError(problems)
        out = ac156(sds, z_over_h)
        return (in_space(out) if space else out), standard
    if standard == "ieee693":
        problems = ieee693_problems(level, damping, level_key, keys["damping"])
        problems += [f"{key}: not with {keys['rrs']} {rrs}: the standard gives it"
                     for key, v in ((keys['rrs_x2'], rrs_x2), (x3_key, rrs_x3)) if v is not None]
        problems += [f"{keys[k]}: only with {keys['rrs']} ac156" for k, v in
                     (("sds", sds), ("z_over_h", z_over_h)) if v is not None]
        if problems:
            raise InputError(problems)
        out = ieee693(level, damping)
        return (in_space(out) if space else out), standard
    problems = [f"{keys[k]}: only with {keys['rrs']} ac156" for k, v in
                (("sds", sds), ("z_over_h", z_over_h)) if v is not None]
    problems += [f"{level_key}: only with {keys['rrs']} ieee693"] if level is not None else []
    out = {}
    files = (("x1", rrs), ("x2", rrs_x2 if rrs_x2 is not None or not space else rrs), ("x3", rrs_x3))
    for axis, name in files:
        if name is None:
            continue
        path = Path(name) if Path(name).is_absolute() else base / name
        try:
            out[axis] = read_rrs(path, damping, f"{Path(name).stem} ({axis})", keys["damping"])
        except InputError as err:
            problems += [p for p in err.problems if p not in problems]  # (x1, x2 may read one file)
    if problems:
        raise InputError(problems)
    return out, None
