"""The verdict of a deck under shock: ``rbhyst shock``.

The shock (a named classical pulse, a pulse of the deck's own, or a record: rbhyst.analyses.shock.drive)
is applied along each axis in both directions, ``shocks`` times one after the other in one run
(MIL-STD-810H Method 516.8 Procedure I: three in each direction of each axis); each run goes on
after the last shock until the free vibration has decayed (rbhyst.analyses.qualification.free_vibration).
The criteria are those of ``rbhyst qualify`` (each element's stroke against its sway space, the
peak total acceleration at G and the points against the equipment's limit, each element's force
against its capacity), the demand the largest over the runs, read from each run's summary.json;
every run must vouch for its accuracy. Each shock's own peaks are given beside the run's, and
how much a later shock's differ from the first's (the hysteresis carried over).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from rbhyst.analyses.qualification import free_vibration
from rbhyst.analyses.qualification.rrs import PLANE_AXES, SPACE_AXES
from rbhyst.analyses.qualification.verdict import (
    Verdict,
    _accuracy,
    accuracy_lines,
    _criteria,
    _deck_with_motion,
    _limit_problems,
    _lowest_frequencies,
    _run_to_rest,
)
from rbhyst.analyses.shock.drive import Drive, G, pulse_drive, record_drive
from rbhyst.errors import InputError
from rbhyst.solve.history import largest_abs
from rbhyst.model.inputs import deck_inputs

#: Q of the drive's shock response spectrum in shock.json and srs.csv (ISO 18431-4's usual)
DRIVE_Q = 10.0
DRIVE_FILE = "drive.csv"
#: a column whose peak is below this share of the largest in its unit is at rest
AT_REST = 1e-6


@dataclass
class ShockRequest:
    """What the shock test is, resolved from the deck's [shock] and the command line."""

    pulse: tuple | None  # (kind, peak m/s2, duration s, compensation, ratio, rise s, what it is)
    record: tuple | None  # (path, units, scale, dt, where)
    axes: list[str]
    shocks: int
    acceleration_limit_g: dict
    force_capacity_N: float | dict | None
    deck_axes: dict
    #: an SRS specification matched per axis (rbhyst.analyses.shock.synthesis): (Specification, q,
    #: method, duration s, seed, Table or None)
    srs: tuple | None = None
    #: the files the shock reads beside the deck: (key, path, as given)
    files: tuple = ()

    @property
    def vertical(self) -> str:
        return next(a for a, what in self.deck_axes.items() if what == "vertical")


def request(deck, cli: dict) -> ShockRequest:
    """The request: the command line's values (``cli``, None where not given) over the deck's
    [shock]; a --pulse or --record there replaces the deck's shock. Problems name the option or
    the deck key they come from, all at once."""
    from rbhyst.model.deck import ACCEL_UNITS
    from rbhyst.model.deck import Pulse as PulseSpec
    from rbhyst.model.shock_pulses import DEFAULT_RATIO, PRESETS

    given = deck.shock.model_dump(exclude_unset=True) if deck.shock is not None else {}
    own = deck.shock
    cli = {k: v for k, v in cli.items() if v is not None}
    space = deck.body is not None and deck.body.dimensions == 3
    deck_axes = dict(SPACE_AXES if space else PLANE_AXES)
    problems, pulse, record = [], None, None
    key = {k: f"--{k.replace('_', '-')}" if k in cli else f"shock.{k}" for k in ("pulse", "record", "units",
                                                                                   "compensation", "shocks", "axes")}
    if "pulse" in cli and "record" in cli:
        problems.append("--record: not with --pulse: give a pulse or a record")
    name = cli.get("pulse") if "record" not in cli else None
    if name is None and "record" not in cli and own is not None and isinstance(own.pulse, str):
        name = own.pulse
    compensation = cli.get("compensation", own.compensation if own is not None else None)
    if compensation is not None and compensation not in ("none", "pre-post"):
        problems.append(f"{key['compensation']}: {compensation!r}: none or pre-post")
    if "compensation" in cli and name is None:
        problems.append("--compensation: only with a named pulse (--pulse, or shock.pulse naming one): a record is "
                        "played as it is, a pulse of the deck's own says its own compensation")
    if "units" in cli and "record" not in cli:
        problems.append("--units: goes with --record (the units of its values)")
    if name is not None:
        if name not in PRESETS:
            problems.append(f"{key['pulse']}: {name!r} is not a pulse rbhyst knows: {', '.join(PRESETS)}")
        else:
            kind, peak_g, duration, cite = PRESETS[name]
            pulse = (kind, peak_g * G, duration, compensation or "none", DEFAULT_RATIO, None,
                     f"{name}: {kind} {peak_g:g} g {1e3 * duration:g} ms ({cite})")
    elif "record" in cli:
        if "units" not in cli:
            problems.append("--units: the units of --record's values (g, m/s2 or cm/s2)")
        elif cli["units"] not in ACCEL_UNITS:
            problems.append(f"--units: {cli['units']!r}: one of {', '.join(ACCEL_UNITS)}")
        record = (Path(cli["record"]).resolve(), cli.get("units"), 1.0, None, "--record")
    elif own is not None and isinstance(own.pulse, PulseSpec):
        p = own.pulse
        if p.start != 0.0:
            problems.append("shock.pulse.start: a shock test's pulse starts at 0 s (leave start out)")
        pulse = (p.type, p.amplitude * ACCEL_UNITS[p.units], p.duration, p.compensation, p.compensation_ratio, p.rise,
                 f"shock.pulse: {p.type} {p.amplitude:g} {p.units} {1e3 * p.duration:g} ms"
                 + (", compensated" if p.compensation != "none" else ""))
    elif own is not None and own.record is not None:
        r = own.record
        path = Path(r.file) if Path(r.file).is_absolute() else deck.base / r.file
        record = (path, r.units, r.scale, r.dt, "shock.record")
    else:
        problems.append("shock: no shock: --pulse NAME (a named pulse), --record FILE --units U, or shock.pulse / "
                        "shock.record in the deck")
    files = () if record is None else ((record[4], record[0], str(cli.get("record") or own.record.file)),)
    axes = cli["axes"] if "axes" in cli else given.get("axes") or list(deck_axes)
    problems += [f"{key['axes']}: {a!r}: an axis of the deck ({', '.join(deck_axes)})" for a in axes
                 if a not in deck_axes]
    if len(set(axes)) != len(axes):
        problems.append(f"{key['axes']}: each axis once")
    shocks = cli.get("shocks", given.get("shocks", 3))
    if not (isinstance(shocks, int) and 1 <= shocks <= 10):
        problems.append(f"{key['shocks']}: {shocks!r}: a whole number from 1 to 10 (in each direction of each axis)")
    limits = {k: given.get(k) for k in ("acceleration_limit_g", "force_capacity_N")}
    problems += [p.replace("qualify.", "shock.").replace("qualify:", "shock:")
                 for p in _limit_problems(deck, limits, space)]
    if problems:
        raise InputError(problems)
    return ShockRequest(pulse, record, list(axes), int(shocks), limits["acceleration_limit_g"] or {},
                        limits["force_capacity_N"], deck_axes, files=files)


def output_files(req: ShockRequest) -> list[str]:
    """The files shock writes (but the plot), to refuse a folder before the work."""
    drives = ([drive_file(a) for a in req.axes] + [f"srs_{a}.csv" for a in req.axes] + ["srs_check.csv"]
              if req.srs is not None else [DRIVE_FILE, "srs.csv"])
    return ["shock.json", *drives] + [f"run_{run_folder(label)}/summary.json" for label in run_labels(req)]


def drive_file(axis: str) -> str:
    """An axis's own drive (an SRS matched per axis)."""
    return f"drive_{axis}.csv"


def run_labels(req: ShockRequest) -> list[str]:
    return [f"{axis}{sign}" for axis in req.axes for sign in ("+", "-")]


def run_folder(label: str) -> str:
    """x1+ -> x1_positive: a folder name without a sign."""
    return label[:-1] + ("_positive" if label.endswith("+") else "_negative")


def make_drive(deck, req: ShockRequest) -> tuple[Drive, float]:
    """The drive and the rest after each shock (free_vibration.tail_s of the deck's modes)."""
    # (the modes need a duration to assemble; a deck for shock alone may have none)
    gap = free_vibration.tail_s(_lowest_frequencies(_deck_with_motion(deck, None, 1.0)))
    if req.pulse is not None:
        return pulse_drive(req.pulse, req.shocks, gap), gap
    path, units, scale, dt, where = req.record
    return record_drive(path, units, scale, dt, req.shocks, gap, where), gap


def make_drives(deck, req: ShockRequest) -> tuple[dict[str, Drive], float, list]:
    """Each shocked axis's drive, the rest after each shock, and the matched records (an SRS
    specification: one of its own an axis, rbhyst.analyses.shock.synthesis; else [] and one drive
    for every axis)."""
    if req.srs is None:
        drive, gap = make_drive(deck, req)
        return {axis: drive for axis in req.axes}, gap, []
    from rbhyst.analyses.shock.drive import repeated
    from rbhyst.analyses.shock.synthesis import make_shocks

    gap = free_vibration.tail_s(_lowest_frequencies(_deck_with_motion(deck, None, 1.0)))
    spec, q, method, duration, seed, table = req.srs
    made = make_shocks(spec, q, duration, method, seed, req.axes, table, vertical=req.vertical)
    drives = {m.axis: repeated(m.acc_g * G, m.dt, req.shocks, gap,
                               f"{spec.name} ({method}, Q = {q:g}, seed {seed}) for {m.axis}") for m in made}
    return drives, gap, made


def shock(deck, req: ShockRequest, folder: Path, integrator: str | None = None, dt: float | None = None,
          tolerance: float | None = None, say=None, command: str | None = None
          ) -> tuple[Verdict, dict[str, Drive], list]:
    """Make the drives, run the deck along each direction of each axis, judge every criterion;
    write into ``folder`` (a staging folder): shock.json, drive.csv and srs.csv (the drive's one
    shock; an SRS matched per axis: drive_<axis>.csv, srs_<axis>.csv and srs_check.csv) and
    run_<axis>_<direction>/summary.json (the plots are the caller's). Returns the verdict, each
    axis's drive and the matched records. ``command``: the command line shock.json's
    ``provenance`` records (None: Python)."""
    from rbhyst.files.provenance import provenance
    from rbhyst.results.writers import deck_as_run, write_srs_csv, write_summary

    inputs = [i for i in deck_inputs(deck) if i[0] == "deck"] + list(req.files)
    started = provenance(command, inputs)

    folder = Path(folder).resolve()  # the runs' decks name the drive's file from their own folder
    drives, gap, made = make_drives(deck, req)
    mark = f"# rbhyst shock {deck.source.name if deck.source else 'deck'}"
    files, facts = {}, {}
    for axis, drive in drives.items():
        name, srs_name = (drive_file(axis), f"srs_{axis}.csv") if made else (DRIVE_FILE, "srs.csv")
        files[axis] = folder / name
        if made or not facts:  # one drive every axis shares is written once
            files[axis].write_text(drive.text(mark), encoding="utf-8")
            srs = drive_srs(drive)
            write_srs_csv(srs, folder / srs_name)
            facts[axis] = drive_facts(drive, srs, gap, name, srs_name)
    if made:
        from rbhyst.analyses.shock.synthesis import check_rows

        (folder / "srs_check.csv").write_text("\n".join(check_rows(made)) + "\n", encoding="utf-8")
    runs, afters, per_shock, notes = [], [], [], []
    labels = run_labels(req)
    for k, label in enumerate(labels, start=1):
        if say is not None:
            say(f"running {label} ({k} of {len(labels)})")
        drive = drives[label[:-1]]
        support = {label[:-1]: {"file": str(files[label[:-1]]), "units": "g",
                                "scale": 1.0 if label.endswith("+") else -1.0}}
        result, s, after = _run_to_rest(deck, support, drive.end, gap, {"integrator": integrator, "dt": dt,
                                                                          "tolerance": tolerance})
        (folder / f"run_{run_folder(label)}").mkdir()
        write_summary(result, folder / f"run_{run_folder(label)}" / "summary.json")
        runs.append((label, s))
        afters.append(after)
        per_shock.append(window_peaks(result, drive))  # (not the rows: a run's table at a time)
        del result
        if after.get("decayed") is False:
            notes.append(f"{label}: the response had not decayed {after['free_vibration_s']:.3g} s after the last "
                         "shock: its peaks are those of the time it ran")
    limits = SimpleNamespace(acceleration_limit_g=req.acceleration_limit_g, force_capacity_N=req.force_capacity_N,
                             axes=req.deck_axes, statistic="max")
    criteria = _criteria(deck, limits, runs)
    shocks = [shock_peaks(windows, [c["column"] for c in criteria]) for windows in per_shock]
    accuracy = _accuracy(runs, deck.analysis.warn_error)
    warnings = [f"{label}: {w}" for label, s in runs for w in s["warnings"]]
    passed = accuracy["pass"] and not warnings and all(c["pass"] for c in criteria)
    worst = min(criteria, key=lambda c: c["margin"]) if criteria else None
    data = {
        "rbhyst_version": _version(),
        "deck": deck.source.name if deck.source else None,
        "pass": passed,
        "drive": (next(iter(facts.values())) if not made else
                  {"per_axis": facts, "shocks_per_direction": req.shocks, "srs_check": "srs_check.csv",
                   "within": all(bool(m.within.all()) for m in made)}),
        "axes": dict(req.deck_axes),
        "shocked_axes": req.axes,
        "runs_per_axis": "both directions: + as the drive is, - with its sign reversed",
        "margin": "1 - demand / capacity: the share of the capacity left (negative: exceeded)",
        "statistic": {"used": "max", "rule": f"the largest over the {len(runs)} runs: each shock a test the equipment "
                                             "must pass"},
        "criteria": [{**{k: v for k, v in c.items() if k not in ("label", "per_motion", "per_motion_pass",
                                                                  "over_capacity")},
                      "per_run": dict(zip(labels, c["per_motion"])),
                      "over_capacity": c["over_capacity"],
                      "worst_run": labels[int(np.argmax(c["per_motion"]))]} for c in criteria],
        "worst": None if worst is None else {"criterion": worst["label"], "margin": worst["margin"],
                                             "run": labels[int(np.argmax(worst["per_motion"]))]},
        "accuracy": {**{k: v for k, v in accuracy.items() if k != "per_motion"},
                     "per_run": [{"run": p.pop("motion"), **p} for p in accuracy["per_motion"]]},
        "warnings": warnings,
        "notes": notes,
        "runs": [{"run": label, "summary": f"run_{run_folder(label)}/summary.json", **after,
                  "shocks": peaks} for label, after, peaks in zip(labels, afters, shocks)],
        "free_vibration": {"rule": free_vibration.RULE, "between_shocks_s": gap},
        "shocks_rule": "runs.<k>.shocks: each shock's own peaks over the output rows from it to the next (the "
                       "criteria are the run's peaks, which see every compute step: a shock's peak between two rows "
                       "is the criteria's, not its own), and the largest change of a later shock's from the first's",
        "deck_as_run": deck_as_run(deck, integrator=integrator, dt=dt, tolerance=tolerance),
        "provenance": started,
    }
    (folder / "shock.json").write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    return Verdict(data, criteria), drives, made


def _version() -> str:
    from rbhyst._version import __version__

    return __version__


def drive_srs(drive: Drive):
    """The shock response spectrum (Q = DRIVE_Q) of one shock of the drive, 12 frequencies an
    octave from 1 Hz to the lesser of 10 kHz and a tenth of its sample rate."""
    from rbhyst.analyses.record_spectrum import default_srs_frequencies
    from rbhyst.solve.shock_spectra import shock_spectrum

    return shock_spectrum(drive.one(), drive.dt, default_srs_frequencies(drive.dt), [1.0 / (2.0 * DRIVE_Q)])


def drive_facts(drive: Drive, srs, gap: float, file: str = DRIVE_FILE, srs_file: str = "srs.csv") -> dict:
    """shock.json's ``drive``: what it is, its timing, its pulse's band check, its SRS's peaks."""
    from rbhyst.model.shock_pulses import table_motion, tolerance_check

    facts = {"source": drive.source, "file": file, "dt_s": drive.dt, "shocks_per_direction": drive.shocks,
             "shock_s": drive.length, "rest_after_each_s": gap, "peak_g": float(np.abs(drive.one()).max() / G)}
    v, x = table_motion(drive.one(), drive.dt)
    facts["table"] = {"end_velocity_m_s": float(v[-1]), "end_displacement_m": float(x[-1]),
                      "peak_velocity_m_s": float(np.abs(v).max()), "peak_displacement_m": float(np.abs(x).max())}
    if drive.pulse is not None:
        p = drive.pulse
        facts["pulse"] = p.describe()
        facts["tolerance"] = tolerance_check(p, p.series.times, p.series.values)
    i, k = int(np.argmax(srs.maximax[:, 0])), int(np.argmax(srs.pv[:, 0]))
    f = srs.frequencies_hz
    facts["srs"] = {"file": srs_file, "q": DRIVE_Q, "frequencies_hz": [float(f[0]), float(f[-1])],
                    "maximax_g": float(srs.maximax[i, 0] / G), "at_hz": float(f[i]),
                    "pv_m_s": float(srs.pv[k, 0]), "pv_at_hz": float(f[k])}
    return facts


def window_peaks(result, drive: Drive) -> list[tuple[float, dict]]:
    """Each shock's own peak |value| of every column of ``result`` (its window: from the shock to
    the next), as (the window's start, {column: peak}): what a run leaves once its rows are gone."""
    t = result.time
    out = []
    for lo, hi in drive.windows():
        inside = (t >= lo) & (t < hi)
        out.append((lo, dict(zip(result.columns, map(float, largest_abs(result.table[inside]))))))
    return out


def shock_peaks(windows: list[tuple[float, dict]], columns: list[str]) -> list[dict]:
    """Each shock's peaks of ``columns`` (window_peaks), and the largest change of a later shock's
    peak against the first's (the hysteresis carried over)."""
    out = [{"from_s": lo, "peaks": {c: peaks[c] for c in dict.fromkeys(columns)}} for lo, peaks in windows]
    first = out[0]["peaks"]
    # a column at rest (its peak below AT_REST of the largest in its unit: a cross response's
    # rounding) has no change worth saying
    unit = {c: "m_s2" if c.endswith("_m_s2") else c.rsplit("_", 1)[-1] for c in first}
    top = {u: max(v for c, v in first.items() if unit[c] == u) for u in set(unit.values())}
    moving = [c for c in first if first[c] > AT_REST * top[unit[c]]]
    for later in out[1:]:
        changes = [abs(later["peaks"][c] - first[c]) / first[c] for c in moving]
        later["largest_change_from_the_first"] = max(changes, default=0.0)
    return out


def verdict_lines(v: Verdict) -> list[str]:
    """The console's account: each failed criterion with the run that failed it, the worst, the verdict."""
    d = v.data
    lines = [f"note: {n}" for n in d["notes"]]
    for c in d["criteria"]:
        over = ", ".join(f"{r} {c['per_run'][r]:.4g} {c['unit']}" for r in c["over_capacity"])
        if not c["pass"]:
            lines.append(f"fail: {c['criterion']} {c['item']}: {c['demand']:.4g} {c['unit']} > {c['capacity']:.4g} "
                         f"{c['unit']} ({over})")
    carried = [(r["run"], s["largest_change_from_the_first"]) for r in d["runs"] for s in r["shocks"][1:]]
    if carried:
        run, most = max(carried, key=lambda x: x[1])
        lines.append(f"note: a later shock's peaks differ from the first's by {100 * most:.2g} % at most ({run}): "
                     "what the shock before left (the mounts' hysteresis, a free vibration not yet decayed), "
                     "over the output rows")
    lines += accuracy_lines(d["accuracy"])
    lines += [f"fail: warning: {w}" for w in d["warnings"]]
    w = d["worst"]
    tail = "" if w is None else f"; least margin {w['margin']:.3g} ({w['criterion']}, run {w['run']})"
    n = len(d["criteria"])
    est = d["accuracy"]["estimated_error"]
    lines.append(f"verdict: {'pass' if v.passed else 'fail'}: {len(d['runs'])} runs of {d['drive']['shocks_per_direction']} "
                 f"shock{'s' * (d['drive']['shocks_per_direction'] != 1)}, {n} criteria, "
                 f"{sum(c['pass'] for c in d['criteria'])} within capacity{tail}; estimated error "
                 f"{'not given' if est is None else f'{100 * est:.2g} %'}")
    return lines
