"""A shock a shaker can play whose SRS meets a specification: ``rbhyst make-shock``.

One component a 1/12-octave frequency f_m of the specification's range, the record their sum:

- **wavelets** (the default; Irvine's wavelet synthesis, after Nelson's WAVSYN):
  a_m sin(2 pi f_m t' / N_m) sin(2 pi f_m t') for 0 <= t' = t - d_m <= N_m / (2 f_m), N_m odd
  and at least 3 half-sines of the envelope, d_m its delay. The product is
  (cos 2 pi f_m (1 - 1/N_m) t' - cos 2 pi f_m (1 + 1/N_m) t') / 2, whose integral and double
  integral over the wavelet are zero when N_m is odd: each wavelet ends at rest by itself.
- **damped-sines** (Smallwood's): a_m exp(-zeta_m 2 pi f_m t') sin(2 pi f_m t') from d_m on,
  zeta_m so that it has decayed to 1 % by the record's end. A damped sine has a net velocity
  and displacement: the sum is compensated by a smooth correction (rbhyst.model.baseline.to_rest
  with a sin^2 window, zero at both ends) that brings both to zero at the end.

Both: the signs and delays (and the N_m) are drawn from numpy's PCG64 seeded by (seed, axis
stream), so that the same seed gives the same record. The amplitudes are iterated by the ratio
aim / SRS at each frequency (the SRS the exact one of rbhyst.solve.shock_spectra, of the record as
its file holds it) until the SRS lies within the band at every frequency with a margin, the aim
the band's middle in dB. A record that asks the table for more than its limits is drawn again
with more half-sines in the low wavelets (more cycles reach the same SRS with less amplitude, so
less displacement and velocity), then longer damped sines; where none fits, the command stops
with what it reached.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rbhyst.analyses.qualification.table import Table, said
from rbhyst.analyses.shock.specification import LOWER_DB, UPPER_DB, Specification, ratio_db, within
from rbhyst.errors import AnalysisError

METHODS = ("wavelets", "damped-sines")
#: the SRS is aimed at the band's middle, dB
AIM_DB = 0.5 * (LOWER_DB + UPPER_DB)
#: the iteration stops this far inside the band (the file's rounding, another SRS code's sampling)
MARGIN_DB = 0.3
MAX_ITERATIONS = 80
#: the samples a period of the highest frequency
SAMPLES_PER_PERIOD = 20
#: the largest number of half-sines a low wavelet may have, try after try (two draws each: more
#: cycles, less displacement and velocity for the same SRS)
HALF_SINES = (9, 9, 19, 19, 39, 39, 79, 79, 159, 159)
#: the least number of half-sines a wavelet has where its record holds more: three make a
#: wavelet so broad that it drives its neighbours' oscillators as much as its own
LEAST_HALF_SINES = 5
#: a try stops when its worst frequency has not come closer to the band over this many iterations
STALLED = 12
#: damped sines' delays within this fraction of the record
DELAY_SHARE = 0.1
#: the least ratio of duration to the lowest frequency's period: three half-sines at 1.5 / f
LEAST_PERIODS = 1.5


@dataclass
class Shock:
    """One axis's record: ``acc_g`` as its file holds it at ``dt`` from 0, its SRS at ``frequency_hz``
    against ``spec`` (m/s2), and what it asks the table."""

    axis: str
    acc_g: np.ndarray
    dt: float
    frequency_hz: np.ndarray
    spec: np.ndarray
    srs: np.ndarray
    iterations: int
    attempt: int
    reached: dict

    @property
    def ratio_db(self) -> np.ndarray:
        return ratio_db(self.srs, self.spec)

    @property
    def within(self) -> np.ndarray:
        return within(self.ratio_db)

    def end_at_rest(self) -> dict:
        """The end velocity and displacement (of the record linear between samples) and their peaks."""
        from rbhyst.model.baseline import integrate

        v, d = integrate(self.acc_g * 9.80665, self.dt)
        return {"end_velocity_m_s": float(v[-1]), "peak_velocity_m_s": float(np.abs(v).max()),
                "end_displacement_m": float(d[-1]), "peak_displacement_m": float(np.abs(d).max())}


def sample_step(spec: Specification) -> float:
    """SAMPLES_PER_PERIOD samples a period of the specification's highest frequency."""
    return 1.0 / (SAMPLES_PER_PERIOD * float(spec.frequency_hz[-1]))


def least_duration(spec: Specification) -> float:
    return LEAST_PERIODS / float(spec.frequency_hz[0])


def wavelet(t: np.ndarray, f: float, n: int, delay: float) -> np.ndarray:
    """sin(2 pi f t' / n) sin(2 pi f t') over 0 <= t' = t - delay <= n / (2 f), 0 elsewhere."""
    tp = t - delay
    inside = (tp >= 0.0) & (tp <= n / (2.0 * f))
    return np.where(inside, np.sin(2.0 * np.pi * f * tp / n) * np.sin(2.0 * np.pi * f * tp), 0.0)


def damped_sine(t: np.ndarray, f: float, zeta: float, delay: float) -> np.ndarray:
    """exp(-zeta 2 pi f t') sin(2 pi f t') from t' = t - delay = 0 on."""
    tp = np.maximum(t - delay, 0.0)
    return np.where(t >= delay, np.exp(-zeta * 2.0 * np.pi * f * tp) * np.sin(2.0 * np.pi * f * tp), 0.0)


def components(method: str, f: np.ndarray, t: np.ndarray, duration: float, rng, attempt: int) -> np.ndarray:
    """The unit components (frequencies x samples), drawn from ``rng``; ``attempt`` from 0 gives
    the low wavelets more half-sines (the damped sines less damping) try after try."""
    out = np.empty((len(f), len(t)))
    for m, fm in enumerate(f):
        if method == "wavelets":
            fits = math.floor(2.0 * fm * duration)  # the half-sines that fit in the record
            top = min(HALF_SINES[attempt], fits)
            top -= (top + 1) % 2  # odd
            least = min(LEAST_HALF_SINES, top)
            n = int(rng.integers(0, (top - least) // 2 + 1)) * 2 + least
            delay = rng.uniform(0.0, duration - n / (2.0 * fm))
            out[m] = wavelet(t, fm, n, delay)
        else:
            delay = rng.uniform(0.0, DELAY_SHARE * duration)
            # decayed to 1 % at the end; longer (less damped) try after try, never below 1 %
            zeta = max(math.log(100.0) / (2.0 * np.pi * fm * (duration - delay)), 0.05 / (1 + attempt))
            out[m] = damped_sine(t, fm, min(zeta, 0.5), delay)
        out[m] *= rng.choice((-1.0, 1.0))
    return out


def compensated(acc: np.ndarray, dt: float) -> np.ndarray:
    """``acc`` brought to rest at its end: velocity and displacement zero, the acceleration's
    start and end untouched (a sin^2 window)."""
    from rbhyst.model.baseline import to_rest

    tau = np.arange(len(acc)) / (len(acc) - 1)
    return to_rest(acc, dt, np.sin(np.pi * tau) ** 2)


def as_in_file(acc: np.ndarray) -> np.ndarray:
    """The values (m/s2) as the file holds them in g."""
    from rbhyst.analyses.qualification.matching import in_file_digits

    return in_file_digits(acc / 9.80665) * 9.80665


def srs_of(acc: np.ndarray, dt: float, f: np.ndarray, q: float) -> np.ndarray:
    """The maximax SRS (m/s2) at ``f`` (rbhyst.solve.shock_spectra, exact to the linear signal)."""
    from rbhyst.solve.shock_spectra import shock_spectrum

    return shock_spectrum(acc, dt, f, [1.0 / (2.0 * q)]).maximax[:, 0]


def matched(spec: Specification, q: float, duration: float, method: str, rng, attempt: int
            ) -> tuple[np.ndarray, np.ndarray, int, bool]:
    """One try: the record (m/s2, as in its file), its SRS at the 1/12-octave frequencies, the
    iterations and whether it lies within the band with the margin."""
    dt = sample_step(spec)
    f = spec.frequencies()
    t = dt * np.arange(math.floor(duration / dt + 1e-9) + 1)
    basis = components(method, f, t, duration, rng, attempt)
    aim = spec(f) * 10.0 ** (AIM_DB / 20.0)
    amp = spec(f) / q  # a start: each component's own oscillator amplifies it about Q times
    lo, hi = LOWER_DB + MARGIN_DB, UPPER_DB - MARGIN_DB
    worst = []
    for k in range(1, MAX_ITERATIONS + 1):
        acc = amp @ basis
        if method == "damped-sines":
            acc = compensated(acc, dt)
        acc = as_in_file(acc)
        srs = srs_of(acc, dt, f, q)
        db = ratio_db(srs, spec(f))
        worst.append(max(float(np.max(lo - db)), float(np.max(db - hi))))
        if worst[-1] <= 0.0:
            return acc, srs, k, True
        if k > STALLED and worst[-1] > 0.99 * min(worst[:-STALLED]):
            return acc, srs, k, False
        amp = amp * aim / srs
    return acc, srs, MAX_ITERATIONS, False


def make_shock(spec: Specification, q: float, duration: float, method: str, seed: int, axis: str, stream: int,
               table: Table | None) -> Shock:
    """The record of one axis: the first try whose SRS lies within the band and that keeps within
    the table's limits (AnalysisError, with what was reached and what would fit, when none does)."""
    dt = sample_step(spec)
    f = spec.frequencies()
    best = closest = None
    tries = len(HALF_SINES)
    for attempt in range(tries):
        rng = np.random.default_rng([seed, stream, attempt])
        acc, srs, iterations, ok = matched(spec, q, duration, method, rng, attempt)
        reached = Table().reached(acc, dt)
        shock = Shock(axis, acc / 9.80665, dt, f, spec(f), srs, iterations, attempt, reached)
        over = table.over(reached) if table is not None else []
        if ok and not over:
            return shock
        if ok and (best is None or _excess(table, reached) < _excess(table, best.reached)):
            best = shock
        if not ok and (closest is None or _outside(shock) < _outside(closest)):
            closest = shock
    if best is None:
        raise AnalysisError(_band_failure(closest, method, tries))
    raise AnalysisError(_table_failure(axis, table, best, spec, duration))


def _outside(shock: Shock) -> float:
    """How far outside the band a record's SRS is at its worst frequency, dB."""
    db = shock.ratio_db
    return max(float(np.max(LOWER_DB - db)), float(np.max(db - UPPER_DB)), 0.0)


def _band_failure(closest: Shock, method: str, tries: int) -> str:
    db = closest.ratio_db
    worst = int(np.argmax(np.maximum(LOWER_DB - db, db - UPPER_DB)))
    other = "damped-sines" if method == "wavelets" else "wavelets"
    return (f"{closest.axis}: no try of {tries} brought the SRS within {LOWER_DB:g}/+{UPPER_DB:g} dB; the closest "
            f"spans {db.min():+.2f} to {db.max():+.2f} dB, worst {db[worst]:+.2f} dB at "
            f"{closest.frequency_hz[worst]:.4g} Hz: --method {other}, another --duration or another --seed would "
            "try again")


def _excess(table: Table, reached: dict) -> float:
    """How far beyond its limits a record is: its largest ratio to a limit."""
    return max(reached[k] / getattr(table, k) for k in ("displacement", "velocity", "acceleration")
               if getattr(table, k) is not None)


def _table_failure(axis: str, table: Table, best: Shock, spec: Specification, duration: float) -> str:
    over = table.over(best.reached)
    asked = "; ".join(f"{k} {said(k, best.reached[k])} against {said(k, getattr(table, k))}" for k in over)
    hint = []
    if {"displacement", "velocity"} & set(over):
        hint.append(f"a longer --duration than {duration:g} s (more cycles in the low wavelets), a specification "
                    f"starting above {spec.frequency_hz[0]:g} Hz or a lower one there")
    if "acceleration" in over:
        hint.append("a higher acceleration limit or a lower specification at its highest frequencies")
    return (f"{axis}: no record within the table's limits after {len(HALF_SINES)} tries; the closest asks {asked}: "
            f"{' or '.join(hint)} would")


def make_shocks(spec: Specification, q: float, duration: float, method: str, seed: int, axes: list[str],
                table: Table | None, vertical: str = "x3") -> list[Shock]:
    """One record an axis, each from its own stream (rbhyst.analyses.qualification.matching.streams:
    x1 1, the vertical 2, the other horizontal 3), so that a deck's axes get the same records
    whether made here or by ``rbhyst qualify --shock``."""
    from rbhyst.analyses.qualification.matching import streams

    return [make_shock(spec, q, duration, method, seed, axis, stream, table)
            for axis, stream in streams(axes, vertical).items()]


def shock_problems(q: float, method: str, keys: dict) -> list[str]:
    """The request's mistakes: an unknown method, a Q out of range."""
    from rbhyst.analyses.shock.specification import q_problems

    problems = q_problems(q, keys.get("q", "--q"))
    if method not in METHODS:
        problems.append(f"{keys.get('method', '--method')}: {method!r}: {' or '.join(METHODS)}")
    return problems


def duration_problem(spec: Specification, duration: float, key: str = "--duration") -> str | None:
    """A record too short to hold the lowest frequency's wavelet (three half-sines: 1.5 / f)."""
    if duration >= least_duration(spec):
        return None
    return (f"{key}: {duration:g} s is too short for {spec.frequency_hz[0]:g} Hz, the specification's lowest "
            f"frequency: {least_duration(spec):.4g} s at least would do (a wavelet of three half-sines lasts 1.5 / f; "
            f"{default_duration(spec):g} s leaves room for more)")


def default_duration(spec: Specification) -> float:
    """Four times the least: room for the low wavelets' cycles and their delays."""
    return round(4.0 * least_duration(spec), 6)


def record_name(shock: Shock) -> str:
    return f"shock_{shock.axis}.csv"


def record_text(shock: Shock, mark: str) -> str:
    """The record as make-motion writes its own: the mark line, ``time_s,acceleration_g``, rows."""
    from rbhyst.analyses.qualification.matching import FILE_FORMAT

    t = shock.dt * np.arange(len(shock.acc_g))
    rows = "\n".join(f"{ti:.9g},{FILE_FORMAT % a}" for ti, a in zip(t, shock.acc_g))
    return f"{mark}: {shock.axis}\ntime_s,acceleration_g\n{rows}\n"


CHECK_COLUMNS = ("axis", "frequency_hz", "spec_g", "srs_g", "ratio_db", "lower_db", "upper_db", "within")


def check_rows(shocks: list[Shock]) -> list[str]:
    """srs_check.csv's lines: a row an axis and 1/12-octave frequency."""
    lines = [",".join(CHECK_COLUMNS)]
    for s in shocks:
        for f, a, b, db, ok in zip(s.frequency_hz, s.spec / 9.80665, s.srs / 9.80665, s.ratio_db, s.within):
            lines.append(f"{s.axis},{f:.6g},{a:.6g},{b:.6g},{db:+.4f},{LOWER_DB:g},{UPPER_DB:g},"
                         f"{'yes' if ok else 'no'}")
    return lines


def summary(shocks: list[Shock], spec: Specification, q: float, method: str, duration: float, seed: int,
            table: Table | None) -> dict:
    """shocks.json: the method, the band and each record's check, timing and table demands."""
    return {
        "specification": spec.name, "q": q, "method": method, "duration_s": duration, "seed": seed,
        "band_db": [LOWER_DB, UPPER_DB], "per_octave": 12,
        "band_source": "MIL-STD-810G Method 516.6 / MIL-STD-810H Method 516.8, 4.2.2 (SRS-specified shock): "
                       "-1.5/+3 dB at 1/12 octave, Q = 10; held at every frequency (the standard allows some "
                       "outside, within -3/+6 dB)",
        "table": None if table is None else table.describe(),
        "records": [{"axis": s.axis, "file": record_name(s), "dt_s": s.dt, "samples": len(s.acc_g),
                     "within": bool(s.within.all()), "ratio_db": [float(s.ratio_db.min()), float(s.ratio_db.max())],
                     "iterations": s.iterations, "try": s.attempt + 1, "peak_g": float(np.abs(s.acc_g).max()),
                     "table_asked": {"displacement_peak_to_peak_m": s.reached["displacement"],
                                     "velocity_m_s": s.reached["velocity"], "acceleration_g": s.reached["acceleration"]},
                     **s.end_at_rest()} for s in shocks],
    }


def shock_lines(shocks: list[Shock]) -> list[str]:
    """The console's account of each record."""
    out = []
    for s in shocks:
        r = s.end_at_rest()
        out.append(f"{s.axis}: SRS {s.ratio_db.min():+.2f} to {s.ratio_db.max():+.2f} dB of the specification at "
                   f"{len(s.frequency_hz)} frequencies (band {LOWER_DB:g}/+{UPPER_DB:g} dB; {s.iterations} iterations); "
                   f"peak {np.abs(s.acc_g).max():.3g} g; asks the table {s.reached['displacement']:.3g} m peak to peak, "
                   f"{s.reached['velocity']:.3g} m/s; ends at {r['end_velocity_m_s']:.2g} m/s, "
                   f"{r['end_displacement_m']:.2g} m")
    return out
