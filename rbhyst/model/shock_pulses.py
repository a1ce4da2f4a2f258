"""Classical shock pulses as a shaker plays them: the main pulse with pre- and post-pulses that
bring the table's velocity and displacement back to zero, their tolerance band, named presets.

A shaker cannot end a shock with a velocity change (its armature would drive away): the main
pulse of area dV is played between a pre-pulse and a post-pulse of the opposite sign (MIL-STD-810H
Method 516.8 draws the classical pulses with them for shaker play). Here both are half-sines
of the same duration D, the main pulse starting as the pre-pulse ends and the post-pulse as it
ends; their peaks b and c solve the two linear conditions of a table at rest at the end

    velocity:      b I_D + c I_D = dV                          (I_D the area of a unit half-sine)
    displacement:  b I_D (-D / 2) + c I_D (T + D / 2) = M      (first moments about the main start)

with M the main pulse's first moment: for a symmetric main pulse b = c; for a terminal-peak
sawtooth the post-pulse is the larger. D is chosen so that the larger of b, c is
``ratio`` x the main peak. Velocity and displacement are zero at the end to rounding, for the
signal as the analysis follows it: the areas and moments are those of the sampled pulse, linear
between its samples (the trapezoidal rule is exact for it).

Tolerances (PULSE_TOLERANCE), as we read MIL-STD-810H Method 516.8 (its figures of the
half-sine, terminal-peak sawtooth and trapezoidal pulses): during the nominal pulse the
acceleration within +-0.2 A of the nominal shape; outside it (the pre- and post-pulses) within
+-0.2 A; the velocity change of the main pulse within +-10 % of nominal. Check the figures of
the revision you test to before relying on these numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.model.records import Series

#: the band about the nominal shape during the pulse and about zero outside it, in units of the
#: peak A, and the velocity change's tolerance (MIL-STD-810H Method 516.8, as read: see the module)
PULSE_TOLERANCE = {"band": 0.2, "outside": 0.2, "velocity_change": 0.10}
#: samples per main pulse: a half-sine linear between 400 samples is within (pi/400)^2/8 = 8e-6 A
#: of its formula; a terminal-peak sawtooth drops to zero over one sample (T / 400)
SAMPLES_PER_PULSE = 400
#: the default peak of the compensation pulses, a fraction of the main peak (within the band outside)
DEFAULT_RATIO = 0.1
#: a trapezoid's default rise (and fall) time, a fraction of its duration
TRAPEZOID_RISE = 0.1


def main_shape(kind: str, tau, rise: float = TRAPEZOID_RISE) -> np.ndarray:
    """The main pulse of peak 1 on tau = (t - start) / duration in [0, 1] (zero outside);
    ``rise`` the trapezoid's rise and fall, a fraction of its duration."""
    from rbhyst.model.signals import SHAPES

    tau = np.asarray(tau, dtype=float)
    on = (tau >= 0.0) & (tau <= 1.0)
    t = np.clip(tau, 0.0, 1.0)
    if kind == "trapezoid":
        value = np.minimum(1.0, np.minimum(t, 1.0 - t) / rise)
    else:
        value = SHAPES[kind][0](t)
    return np.where(on, value, 0.0)


@dataclass(frozen=True)
class ClassicalPulse:
    """A classical pulse as samples (``series``: zero before ``series.t0`` and after its end) and its
    parts: the nominal main pulse (``kind``, peak ``amplitude``, ``duration``, from ``main_start``),
    the pre- and post-pulses' peaks (opposite sign, 0 without compensation) and duration."""

    series: Series
    kind: str
    amplitude: float
    duration: float
    main_start: float
    rise: float
    pre_peak: float = 0.0
    post_peak: float = 0.0
    compensation_duration: float = 0.0

    @property
    def main_end(self) -> float:
        return self.main_start + self.duration

    def nominal(self, t) -> np.ndarray:
        """The main pulse alone, as the standard draws it."""
        return self.amplitude * main_shape(self.kind, (np.asarray(t, float) - self.main_start) / self.duration,
                                           self.rise)

    def describe(self) -> dict:
        dt = self.series.dt
        v, d = table_motion(self.series.values, dt)
        return {"type": self.kind, "amplitude_m_s2": self.amplitude, "duration_s": self.duration,
                "main_start_s": self.main_start, "rise_s": self.rise * self.duration if self.kind == "trapezoid"
                else None,
                "compensation": "pre-post" if self.compensation_duration > 0 else "none",
                "pre_pulse_peak_m_s2": self.pre_peak, "post_pulse_peak_m_s2": self.post_peak,
                "compensation_duration_s": self.compensation_duration, "dt_s": dt,
                "end_velocity_m_s": float(v[-1]), "end_displacement_m": float(d[-1]),
                "peak_velocity_m_s": float(np.abs(v).max()), "peak_displacement_m": float(np.abs(d).max())}


def table_motion(acc, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement from rest of an acceleration linear between samples, exactly:
    v by the trapezoidal rule, x by the integral of that piecewise-quadratic velocity."""
    a = np.asarray(acc, dtype=float)
    v = np.concatenate([[0.0], np.cumsum(0.5 * dt * (a[1:] + a[:-1]))])
    x = np.concatenate([[0.0], np.cumsum(dt * v[:-1] + dt * dt * (a[:-1] / 3.0 + a[1:] / 6.0))])
    return v, x


def classical_pulse(kind: str, amplitude: float, duration: float, start: float = 0.0,
                    compensation: str = "none", ratio: float = DEFAULT_RATIO,
                    rise: float | None = None) -> ClassicalPulse:
    """The pulse as samples; with ``compensation = "pre-post"`` the pre-pulse starts at ``start``
    and the main pulse follows it (see the module). ``rise``: a trapezoid's rise and fall, s
    (default TRAPEZOID_RISE of the duration)."""
    rise_f = (TRAPEZOID_RISE if rise is None else rise / duration) if kind == "trapezoid" else TRAPEZOID_RISE
    dt = duration / SAMPLES_PER_PULSE
    main = amplitude * main_shape(kind, np.arange(SAMPLES_PER_PULSE + 1) / SAMPLES_PER_PULSE, rise_f)
    if kind == "terminal-peak-sawtooth":  # the drop over the step after the peak
        main = np.append(main, 0.0)
    if compensation == "none":
        return ClassicalPulse(Series(start, dt, main), kind, amplitude, duration, start, rise_f)
    # the compensation pulses' duration for peaks of about ratio x A: for a symmetric pulse
    # b = c = dV / (2 I_D), I_D = 2 D / pi; the asymmetric ones are refined below on the samples
    area = float(np.sum(0.5 * dt * (main[1:] + main[:-1])))
    n = max(2, round(math.pi * abs(area) / (4.0 * ratio * abs(amplitude)) / dt))
    for _ in range(60):
        b, c, unit = _compensation_peaks(main, dt, n)
        biggest = max(abs(b), abs(c))
        if biggest <= ratio * abs(amplitude) * (1.0 + 1e-9):
            break
        n = math.ceil(n * biggest / (ratio * abs(amplitude)))
    values = np.concatenate([-b * unit, main[1:], -c * unit[1:]])
    return ClassicalPulse(Series(start, dt, values), kind, amplitude, duration, start + n * dt, rise_f,
                          float(-b), float(-c), n * dt)


def _compensation_peaks(main: np.ndarray, dt: float, n: int) -> tuple[float, float, np.ndarray]:
    """Peaks b, c of the half-sines of n steps before and after ``main`` (sampled at dt, its first
    sample where the pre-pulse ends) that take the velocity and the displacement to zero, and a
    unit half-sine of n steps. Exact for the samples, linear between them."""
    unit = np.sin(np.pi * np.arange(n + 1) / n)
    t_main = np.arange(len(main)) * dt
    big_t = t_main[-1]
    t_unit = np.arange(n + 1) * dt

    def area_moment(values, t):  # of the piecewise-linear signal: trapezoidal and exact linear moments
        a0, a1, t0, t1 = values[:-1], values[1:], t[:-1], t[1:]
        area = np.sum(0.5 * dt * (a0 + a1))
        moment = np.sum(dt * (a0 * (2 * t0 + t1) + a1 * (t0 + 2 * t1)) / 6.0)
        return float(area), float(moment)

    a_main, m_main = area_moment(main, t_main)
    a_u, m_pre = area_moment(unit, t_unit - n * dt)  # the pre-pulse ends at the main start (t = 0)
    _, m_post = area_moment(unit, t_unit + big_t)
    # b (a_u, m_pre) + c (a_u, m_post) = (a_main, m_main): the table's velocity and displacement to zero
    b, c = np.linalg.solve(np.array([[a_u, a_u], [m_pre, m_post]]), np.array([a_main, m_main]))
    return float(b), float(c), unit


def tolerance_check(pulse: ClassicalPulse, t, acc) -> dict:
    """The acceleration ``acc`` at times ``t`` (a played or computed pulse) against PULSE_TOLERANCE
    of ``pulse``: the largest deviation from the nominal during the main pulse and the largest
    acceleration outside it, in units of the peak; the velocity change of the main pulse against
    its nominal; pass when all three are within."""
    t = np.asarray(t, dtype=float)
    a = np.asarray(acc, dtype=float)
    peak = abs(pulse.amplitude)
    inside = (t >= pulse.main_start) & (t <= pulse.main_end)  # (a sawtooth's drop after its peak: outside)
    deviation = float(np.max(np.abs(a[inside] - pulse.nominal(t[inside])), initial=0.0)) / peak
    outside = float(np.max(np.abs(a[~inside]), initial=0.0)) / peak
    ti, ai = t[inside], a[inside]
    dv = float(np.sum(0.5 * np.diff(ti) * (ai[1:] + ai[:-1]))) if len(ti) > 1 else 0.0
    nominal_dv = float(np.sum(0.5 * np.diff(ti) * (pulse.nominal(ti)[1:] + pulse.nominal(ti)[:-1]))) \
        if len(ti) > 1 else 0.0
    error_dv = abs(dv - nominal_dv) / abs(nominal_dv) if nominal_dv else 0.0
    tol = PULSE_TOLERANCE
    return {"band": tol["band"], "deviation": deviation, "outside_limit": tol["outside"], "outside": outside,
            "velocity_change_m_s": dv, "nominal_velocity_change_m_s": nominal_dv,
            "velocity_change_error": error_dv, "velocity_change_tolerance": tol["velocity_change"],
            "pass": bool(deviation <= tol["band"] and outside <= tol["outside"]
                         and error_dv <= tol["velocity_change"]),
            "source": "MIL-STD-810H Method 516.8, its figures of the classical pulses (as read)"}


#: named pulses: (type, peak in g, duration in s, where from). The terminal-peak sawtooth
#: defaults of MIL-STD-810H Method 516.8 (Procedure I functional test; Procedure V crash hazard)
#: for equipment without measured data, as we read its tables; the 15 g 11 ms half-sine of
#: MIL-STD-810C's Procedure I; the half-sines of MIL-STD-202H Method 213 test conditions.
PRESETS = {
    "810h-functional-flight": ("terminal-peak-sawtooth", 20.0, 0.011,
                               "MIL-STD-810H 516.8 Procedure I, flight vehicle materiel"),
    "810h-functional-ground": ("terminal-peak-sawtooth", 40.0, 0.011, "MIL-STD-810H 516.8 Procedure I, ground materiel"),
    "810h-crash-flight": ("terminal-peak-sawtooth", 40.0, 0.011, "MIL-STD-810H 516.8 Procedure V, flight vehicle materiel"),
    "810h-crash-ground": ("terminal-peak-sawtooth", 75.0, 0.006, "MIL-STD-810H 516.8 Procedure V, ground materiel"),
    "810c-basic-design": ("half-sine", 15.0, 0.011, "MIL-STD-810C 516.2 Procedure I"),
    "202-condition-a": ("half-sine", 50.0, 0.011, "MIL-STD-202H Method 213, test condition A"),
}
