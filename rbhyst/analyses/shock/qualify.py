"""``rbhyst qualify --shock FILE.csv`` / ``--pulse NAME`` / ``[qualify] shock``: a shock
qualification, run by the shock workflow (rbhyst.analyses.shock.verdict) with qualify's limits.

It writes what ``rbhyst shock`` writes (shock.json, the drives and their spectra, each run's
summary) and qualification.json: the verdict in the shape of a seismic qualification's (pass,
criteria with each run's demand, worst, accuracy, warnings, notes, runs), ``kind = "shock"``
and a pointer to shock.json for the drives and each shock's own peaks.
"""

from __future__ import annotations

from pathlib import Path

from rbhyst.analyses.shock.verdict import ShockRequest
from rbhyst.errors import AnalysisError, InputError

#: qualify's seismic options, which a shock qualification does not take
SEISMIC = ("standard", "sds", "z_over_h", "level", "rrs", "rrs_x2", "rrs_x3", "rrs_damping", "motions",
           "motion_dt", "statistic")


def wanted(deck, cli: dict) -> bool:
    """Whether the command asks for a shock qualification (an option or the deck's qualify.shock)."""
    own = deck.qualify.shock if deck.qualify is not None else None
    return cli.get("shock") is not None or cli.get("pulse") is not None or own is not None


def request(deck, cli: dict) -> ShockRequest:
    """The shock request from ``cli`` (qualify's options, None where not given) over the deck's
    [qualify] shock and its limits; problems name the option or deck key, all at once."""
    from rbhyst.analyses.qualification.rrs import PLANE_AXES, SPACE_AXES
    from rbhyst.analyses.qualification.table import Table, read_table
    from rbhyst.analyses.qualification.verdict import _limit_problems
    from rbhyst.analyses.shock.drive import G
    from rbhyst.analyses.shock.specification import read_specification
    from rbhyst.analyses.shock.synthesis import default_duration, duration_problem, shock_problems
    from rbhyst.model.shock_pulses import DEFAULT_RATIO, PRESETS

    q_deck = deck.qualify
    own = q_deck.shock if q_deck is not None else None
    given = own.model_dump(exclude_unset=True) if own is not None else {}
    problems = [f"--{k.replace('_', '-')}: not with a shock qualification (--shock, --pulse or qualify.shock)"
                for k in SEISMIC if cli.get(k) is not None]
    space = deck.body is not None and deck.body.dimensions == 3
    deck_axes = dict(SPACE_AXES if space else PLANE_AXES)
    if cli.get("shock") is not None and cli.get("pulse") is not None:
        problems.append("--pulse: not with --shock: an SRS specification or a named pulse")
    srs_path = cli.get("shock")
    name = cli.get("pulse")
    if srs_path is None and name is None and own is not None:
        srs_path = None if own.srs is None else (Path(own.srs) if Path(own.srs).is_absolute() else deck.base / own.srs)
        name = own.pulse
    pulse = srs = None
    if name is not None:
        compensation = given.get("compensation") or "none"
        if name not in PRESETS:
            problems.append(f"{'--pulse' if cli.get('pulse') else 'qualify.shock.pulse'}: {name!r} is not a pulse "
                            f"rbhyst knows: {', '.join(PRESETS)}")
        else:
            kind, peak_g, duration, cite = PRESETS[name]
            pulse = (kind, peak_g * G, duration, compensation, DEFAULT_RATIO, None,
                     f"{name}: {kind} {peak_g:g} g {1e3 * duration:g} ms ({cite})")
    elif srs_path is not None:
        key = "--shock" if cli.get("shock") else "qualify.shock"
        method, q = given.get("method", "wavelets"), given.get("q", 10.0)
        problems += [p.replace("--", "qualify.shock.") for p in shock_problems(q, method, {})]
        table, table_problems = read_table(cli["table"]) if cli.get("table") else (None, [])
        problems += table_problems
        if table is None and given.get("table"):
            table = Table(**given["table"])
        try:
            spec = read_specification(Path(srs_path))
        except InputError as err:
            problems += [f"{key}: {p}" for p in err.problems]
            spec = None
        if spec is not None:
            duration = cli.get("duration") or given.get("duration") or default_duration(spec)
            short = duration_problem(spec, duration, "--duration" if cli.get("duration") else "qualify.shock.duration")
            if short and not problems:
                raise AnalysisError(short)
            seed = cli["seed"] if cli.get("seed") is not None else given.get("seed", 1)
            srs = (spec, q, method, duration, seed, table)
    else:
        problems.append("qualify.shock: an srs (a CSV specification) or a pulse (a named one)")
    axes = given.get("axes") or list(deck_axes)
    problems += [f"qualify.shock.axes: {a!r}: an axis of the deck ({', '.join(deck_axes)})" for a in axes
                 if a not in deck_axes]
    limits = {"acceleration_limit_g": q_deck.acceleration_limit_g if q_deck else None,
              "force_capacity_N": q_deck.force_capacity_N if q_deck else None}
    problems += _limit_problems(deck, limits, space)
    if problems:
        raise InputError(problems)
    files = () if srs is None else (("--shock" if cli.get("shock") else "qualify.shock.srs", Path(srs_path),
                                     str(cli.get("shock") or own.srs)),)
    return ShockRequest(pulse, None, list(axes), int(given.get("shocks", 3)), limits["acceleration_limit_g"] or {},
                        limits["force_capacity_N"], deck_axes, srs, files)


def qualification(data: dict) -> dict:
    """qualification.json of a shock qualification: shock.json's verdict in a seismic one's shape."""
    keep = ("rbhyst_version", "deck", "pass", "criteria", "worst", "accuracy", "warnings", "notes", "provenance")
    return {**{k: data[k] for k in keep if k in data}, "kind": "shock", "details": "shock.json",
            "axes": data["axes"], "shocked_axes": data["shocked_axes"],
            "shocks_per_direction": data["drive"]["shocks_per_direction"],
            "runs": [{"run": r["run"], "summary": r["summary"]} for r in data["runs"]]}
