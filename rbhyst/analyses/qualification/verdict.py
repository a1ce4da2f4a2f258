"""The verdict of a deck against a required response spectrum: ``rbhyst qualify``.

The motions are made (spectrum-compatible, rbhyst.analyses.qualification.matching) or taken
from the deck, their TRS checked, the deck run once per motion (x1 horizontal, x2 vertical; a
deck in space: x1 and x2 horizontal, x3 vertical) and
every criterion the deck gives compared with its capacity: each element's stroke, the peak total
acceleration at G and at each point of interest against the equipment's limit, each element's
force against its capacity. The demand is the run's own figure (summary.json's peaks and
strokes); over several motions it is, by ``qualify.statistic``, the largest ("max", the default:
a test lab runs each motion as a test of its own, and the equipment must pass every one), or
their mean from seven motions on ("mean": the rule of ASCE 7-10, 16.2.4, for an analysis by
response histories; with fewer motions the largest). Every motion whose own demand exceeds a
capacity is named, whatever the statistic. A run whose error estimate exceeds
``analysis.warn_error``, that is ``sensitive``, that has no estimate, or that warns, cannot vouch
for its demands: the verdict is then a fail, whatever the margins.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rbhyst.analyses.qualification import free_vibration, matching, strong_motion
from rbhyst.analyses.qualification.table import Table, read_table, table_problems
from rbhyst.analyses.qualification.rrs import PLANE_AXES, SPACE_AXES, STANDARDS, G, RRS, requested_rrs
from rbhyst.errors import InputError
from rbhyst.model.inputs import deck_inputs, resolved

#: with statistic = "mean": from this many motions on the demand is the mean over them, below it
#: the largest (ASCE 7-10 16.2.4)
MEAN_FROM = 7
STATISTICS = ("max", "mean")
_SPECTRUM_KEYS = ("standard", "sds", "z_over_h", "level", "rrs", "rrs_x2", "rrs_x3", "rrs_damping")


@dataclass
class Request:
    """What to qualify against, resolved from the deck's [qualify] and the command line."""

    rrs: dict[str, RRS]
    standard: str | None
    motions: int | str
    seed: int
    duration: float
    motion_dt: float
    acceleration_limit_g: dict
    force_capacity_N: float | dict | None
    #: what each axis of the deck is: x1 horizontal, x2 vertical (PLANE_AXES); in space x1 and
    #: x2 horizontal, x3 vertical (SPACE_AXES)
    axes: dict = field(default_factory=lambda: dict(PLANE_AXES))
    #: the demand over the motions: "max" or "mean" (see the module)
    statistic: str = "max"
    #: the shake table's limits (table.Table; None: none)
    table: object = None
    #: the RRS files read: (deck key or option, path, name as given), for the report's checksums
    files: list = field(default_factory=list)

    @property
    def vertical(self) -> str:
        return next(a for a, what in self.axes.items() if what == "vertical")


def request(deck, cli: dict) -> Request:
    """The request: the command line's values (``cli``, None where not given) over the deck's
    [qualify]; a --standard or --rrs there replaces the deck's spectrum. Problems name the option
    or the deck key they come from, all at once."""
    given = deck.qualify.model_dump(exclude_unset=True) if deck.qualify is not None else {}
    cli = {k: v for k, v in cli.items() if v is not None}
    space = deck.body is not None and deck.body.dimensions == 3
    for k in ("rrs", "rrs_x2", "rrs_x3"):  # files named on the command line are where the command runs
        if k in cli and cli[k].lower() not in STANDARDS:
            cli[k] = str(Path(cli[k]).resolve())
    if "standard" in cli or "rrs" in cli:
        given = {k: v for k, v in given.items() if k not in _SPECTRUM_KEYS}
    values = {**given, **cli}
    option = {"standard": "--standard", "rrs": "--rrs", "rrs_x2": "--rrs-x2", "rrs_x3": "--rrs-x3",
              "rrs_damping": "--rrs-damping",
              "sds": "--sds", "z_over_h": "--z-over-h", "level": "--level", "motions": "--motions",
              "duration": "--duration",
              "motion_dt": "--motion-dt", "seed": "--seed", "statistic": "--statistic", "table": "--table"}
    keys = {k: option[k] if k in cli else f"qualify.{k}" for k in option}
    problems = []
    if "standard" in values and "rrs" in values:
        problems.append(f"{keys['rrs']}: not with {keys['standard']}: give a standard or RRS files")
    if "standard" in cli and cli["standard"].lower() not in STANDARDS:
        problems.append(f"--standard: {cli['standard']!r}: {' or '.join(STANDARDS)} (or RRS files with --rrs)")
    if "standard" not in values and "rrs" not in values:
        problems.append("qualify: no required response spectrum: --standard ac156 (with --sds and --z-over-h), "
                        "--standard ieee693 (with --level), --rrs FILE, or the same keys in the deck's [qualify]")
    motions = values.get("motions", 1)
    if isinstance(motions, str) and motions != "deck":
        try:
            motions = int(motions)
        except ValueError:
            problems.append(f"{keys['motions']}: {motions!r}: a number of motions to make, or deck")
            motions = 1
    if isinstance(motions, int) and motions < 1:
        problems.append(f"{keys['motions']}: {motions}: at least 1")
    limits = values.get("table")
    if isinstance(limits, str):
        limits, said = read_table(limits, keys["table"])
        problems += said
    elif isinstance(limits, dict):
        limits = Table(**{k: v for k, v in limits.items() if v is not None}) if any(limits.values()) else None
    if values.get("statistic", "max") not in STATISTICS:
        problems.append(f"{keys['statistic']}: {values['statistic']!r}: max (the largest over the motions) or mean "
                        f"(their mean from {MEAN_FROM} motions on, ASCE 7-10 16.2.4)")
    rrs, standard = {}, None
    if not problems:
        spec_keys = {"rrs": keys["standard"] if "standard" in values else keys["rrs"], "rrs_x2": keys["rrs_x2"],
                     "rrs_x3": keys["rrs_x3"], "damping": keys["rrs_damping"], "sds": keys["sds"], "z_over_h": keys["z_over_h"],
                     "level": keys["level"], "duration": keys["duration"], "dt": keys["motion_dt"]}
        try:
            rrs, standard = requested_rrs(values.get("standard", values.get("rrs")), values.get("rrs_x2"),
                                          values.get("rrs_damping"), values.get("sds"), values.get("z_over_h"),
                                          deck.base, spec_keys, values.get("level"), values.get("rrs_x3"), space)
        except InputError as err:
            problems += err.problems
        if rrs and motions != "deck":
            problems += matching.motion_problems(rrs, values.get("duration", 30.0), values.get("motion_dt", 0.005),
                                                 None, standard, spec_keys)
            problems += table_problems(limits, {a: None if r.peak_min is None else r.peak_min / G
                                                for a, r in rrs.items()}, keys["table"])
        if limits is not None and motions == "deck":
            problems.append(f"{keys['table']}: with motions made (not the deck's own, which are as they are)")
    problems += _limit_problems(deck, values, space)
    gravity = deck.body.gravity if deck.body is not None else None
    if gravity is not None and not space and abs(gravity[0]) > abs(gravity[1]):
        problems.append("body.gravity: acts along x1, but qualification takes x1 as horizontal and x2 as vertical "
                        "(the vertical spectrum drives x2)")
    if gravity is not None and space and abs(gravity[2]) < max(abs(gravity[0]), abs(gravity[1])):
        along = "x1" if abs(gravity[0]) >= abs(gravity[1]) else "x2"
        problems.append(f"body.gravity: acts along {along}, but qualification takes x1 and x2 as horizontal and x3 "
                        "as vertical in space (the vertical spectrum drives x3)")
    if problems:
        raise InputError(problems)
    files = [(keys[k], resolved(values[k], deck.base), values[k]) for k in ("rrs", "rrs_x2", "rrs_x3")
             if standard is None and isinstance(values.get(k), str)]
    return Request(rrs, standard, motions, int(values.get("seed", 1)), float(values.get("duration", 30.0)),
                   float(values.get("motion_dt", 0.005)), values.get("acceleration_limit_g") or {},
                   values.get("force_capacity_N"), dict(SPACE_AXES if space else PLANE_AXES),
                   values.get("statistic", "max"), limits, files)


def output_files(req: Request) -> list[str]:
    """The files qualify writes (but the plot), to refuse a folder before the work."""
    n = 1 if req.motions == "deck" else req.motions
    files = ["qualification.json"] + [f"run_{k}/summary.json" for k in range(1, n + 1)]
    if req.motions != "deck":
        files += ["trs.csv", "trs_fine.csv", "records.csv", "motions.json"] + [f"motions/m{k}_{axis}.csv" for k in range(1, n + 1) for axis in req.rrs]
    return files


def _limit_problems(deck, values: dict, space: bool = False) -> list[str]:
    problems = []
    names = [p.name for p in deck.output.points or []]
    for name, limit in (values.get("acceleration_limit_g") or {}).items():
        if name != "G" and name not in names:
            problems.append(f"qualify.acceleration_limit_g.{name}: no point {name!r} in output.points "
                            f"({', '.join(names + ['G (the mass centre)'])})")
        n = 3 if space else 2
        if isinstance(limit, list) and len(limit) != n:
            said = "[x1, x2, x3] (the deck is in space)" if space else "[x1, x2] (the deck is in the plane)"
            problems.append(f"qualify.acceleration_limit_g.{name}: {len(limit)} values: one number for every "
                            f"direction or {said}")
    caps = values.get("force_capacity_N")
    n_el = sum(el.count for el in deck.all_elements)
    if isinstance(caps, dict):
        for name in caps:
            if not (name.startswith("e") and name[1:].isdigit() and 1 <= int(name[1:]) <= n_el):
                problems.append(f"qualify.force_capacity_N.{name}: not an element: e1 to e{n_el}, as in "
                                "time_history.csv (count expanded)")
    strokes = any(el.stroke is not None for el in deck.all_elements)
    if not (strokes or values.get("acceleration_limit_g") or caps):
        problems.append("qualify: nothing to hold the deck to: give elements a stroke, or "
                        "qualify.acceleration_limit_g (per point, g) or qualify.force_capacity_N")
    return problems


# ---------------------------------------------------------------- the runs


def _deck_with_motion(deck, support: dict | None, duration: float | None = None, notes: list | None = None):
    """A copy of the deck driven by ``support`` (None: its own), whose analysis lasts at least
    ``duration`` (the motion and its free vibration; a shorter analysis.duration is lengthened,
    with a note; None analysis.duration: the motion's end)."""
    from rbhyst.model.deck import parse_deck

    data = deck.model_dump(mode="python", exclude_unset=True)
    if support is not None:
        ex = dict(data.get("excitation") or {})
        ex["support"] = support
        data["excitation"] = ex
    own = data["analysis"].get("duration")
    if duration is not None and (own is None or own < duration):
        data["analysis"] = {**data["analysis"], "duration": duration}
    if duration is not None and own is not None and own < duration:
        if notes is not None and not notes:
            notes.append(f"analysis.duration: {own:g} s is shorter than the motions and their free vibration "
                         f"({duration:g} s): each run covers them")
    copy = parse_deck(data)
    copy._source = deck.source
    return copy


def _support(files: dict[str, Path]) -> dict:
    return {axis: {"file": str(path), "units": "g"} for axis, path in files.items()}


@dataclass
class Verdict:
    """What qualification.json holds."""

    data: dict
    criteria: list[dict]
    checks: dict = field(default_factory=dict)  # axis -> [(label, Check)] for the plot
    heading: tuple[str, ...] = ()  # what the plot says above the bars

    @property
    def passed(self) -> bool:
        return bool(self.data["pass"])


def qualify(deck, req: Request, folder: Path, integrator: str | None = None, dt: float | None = None,
            tolerance: float | None = None, say=None, command: str | None = None) -> Verdict:
    """Make or take the motions, run the deck on each, judge every criterion; write into ``folder``
    (a staging folder): qualification.json, trs.csv, motions.json (with motions made), the
    motions' records and run_<k>/summary.json (the plot is the caller's: report.qualification).
    ``command``: the command line qualification.json's ``provenance`` records (None: Python).

    Long because it is the qualification's pipeline read top to bottom: the motions, their
    check, the runs, the criteria."""
    from rbhyst._version import __version__
    from rbhyst.files.provenance import provenance
    from rbhyst.results.writers import deck_as_run, write_summary

    folder = Path(folder).resolve()  # the runs' decks name the motions' files from their own folder
    facts = provenance(command, qualification_inputs(deck, req))
    runs = []  # (label, summary dict)
    notes: list[str] = []
    given = _own_motion(deck, req) if req.motions == "deck" else _made_motions(deck, req, folder, notes)
    decks, motion_facts, checks = given.decks, given.facts, given.checks
    afters: list[dict] = []
    trs_ok, peak_ok, band_ok, strong_ok = given.ok, given.peak_ok, given.band_ok, given.strong_ok
    tail = None
    for k, (label, support, end) in enumerate(decks, start=1):
        if say is not None:
            say(f"running {label} ({k} of {len(decks)})")
        if tail is None:  # the structure is every motion's: its modes, once
            tail = free_vibration.tail_s(_lowest_frequencies(_deck_with_motion(deck, support)))
        result, s, after = _run_to_rest(deck, support, end, tail, dict(integrator=integrator, dt=dt,
                                                                       tolerance=tolerance))
        (folder / f"run_{k}").mkdir()
        write_summary(result, folder / f"run_{k}" / "summary.json")  # as rbhyst run writes it
        runs.append((label, s))
        afters.append({"motion": label, **after})
        if after.get("decayed") is False:
            column, g = max(after["grown"].items(), key=lambda kv: kv[1])
            notes.append(f"{label}: the response had not decayed {after['free_vibration_s']:.3g} s after the motion "
                         f"(the peak of {column} grew by {100 * g:.3g} % in its last half): its peaks are those of "
                         "the time it ran")
    criteria = _criteria(deck, req, runs)
    accuracy = _accuracy(runs, deck.analysis.warn_error)
    warnings = [f"{label}: {w}" for label, s in runs for w in s["warnings"]]
    n = len(runs)
    passed = trs_ok and accuracy["pass"] and not warnings and all(c["pass"] for c in criteria)
    data = {
        "rbhyst_version": __version__,
        "deck": deck.source.name if deck.source else None,
        "pass": passed,
        "standard": req.standard,
        "rrs": {axis: r.describe() for axis, r in req.rrs.items()},
        "axes": dict(req.axes),
        "motions": motion_facts,
        "statistic": statistic_facts(req.statistic, n),
        "table": None if req.table is None else req.table.describe(),
        "margin": "1 - demand / capacity: the share of the capacity left (negative: exceeded)",
        "criteria": [{k: v for k, v in c.items() if k != "label"} for c in criteria],
        "trs": {"pass": trs_ok, "band": {axis: list(r.band) for axis, r in req.rrs.items()},
                "check_range_hz": {axis: list(r.check_range) for axis, r in req.rrs.items()},
                "max_correlation": matching.MAX_CORRELATION,
                "peak_min_g": {axis: None if r.peak_min is None else r.peak_min / G for axis, r in req.rrs.items()},
                "within_band": band_ok, "peak_pass": peak_ok,
                "strong_motion_min_s": {axis: r.strong_min_s for axis, r in req.rrs.items()},
                "strong_motion_pass": strong_ok, "strong_motion_definition": strong_motion.DEFINITION},
        "accuracy": accuracy,
        "warnings": warnings,
        "notes": notes,
        "runs": [{"motion": label, "summary": f"run_{k}/summary.json", **after}
                 for k, ((label, _), after) in enumerate(zip(runs, afters), start=1)],
        "free_vibration": {"rule": free_vibration.RULE},
        # the deck as given, with the command's overrides (each made motion takes excitation.support's place)
        "deck_as_run": deck_as_run(deck, integrator=integrator, dt=dt, tolerance=tolerance),
        "provenance": facts,
    }
    (folder / "qualification.json").write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    est = accuracy["estimated_error"]
    heading = (f"TRS within the band: {'yes' if trs_ok else 'no'}",
               f"estimated error {'not given' if est is None else f'{100 * est:.2g} %'} "
               f"(at most {100 * deck.analysis.warn_error:g} %)",
               f"warnings: {len(warnings) or 'none'}", data["statistic"]["rule"])
    return Verdict(data, criteria, checks, heading)


@dataclass
class GivenMotions:
    """The motions a qualification runs: each one's deck, its facts, its TRS checks per axis and
    whether they meet the RRS's rules."""

    decks: list  # (label, support (None: the deck's own), the motion's end in s or None)
    facts: list[dict]
    checks: dict  # axis -> [(label, Check)]
    band_ok: bool = True  # every TRS within its band (and made motions' components independent)
    peak_ok: bool = True  # every peak acceleration at least the least
    strong_ok: bool = True  # every record's strong motion at least the least (None measured: not judged)

    @property
    def ok(self) -> bool:
        return self.band_ok and self.peak_ok and self.strong_ok


def _lowest_frequencies(deck) -> tuple[float, ...]:
    """The natural frequencies (Hz) of the deck's initial system (rbhyst.solve.modes)."""
    from rbhyst.model.system import assemble
    from rbhyst.solve.modes import initial_modes

    return initial_modes(assemble(deck, deck.base)).frequencies_hz


def _run_to_rest(deck, support, end: float | None, tail: float, options: dict):
    """The run of the deck on ``support`` through its motion (ending at ``end``) and the free
    vibration after it (rbhyst.analyses.qualification.free_vibration): the result, its summary
    and what the tail was."""
    from rbhyst.results.analysis import run_deck

    if end is None:  # no end to the motion: the deck's own duration, no tail
        result = run_deck(_deck_with_motion(deck, support), keep=False, **options)
        return result, result.summary(), {}
    for attempt in range(free_vibration.TAIL_TRIES):
        d = _deck_with_motion(deck, support, end + tail)
        result = run_deck(d, keep=True, **options)  # (the rows: the peaks before and after half the tail)
        s = result.summary()
        stop = s["analysis"]["duration_s"]
        columns = {c: result.column(c) for c in result.columns if c != "time_s"}
        growth = free_vibration.grown(result.time, columns, end + 0.5 * (stop - end), d.analysis.warn_error)
        if not growth or attempt == free_vibration.TAIL_TRIES - 1:
            break
        tail *= free_vibration.TAIL_GROWTH
    return result, s, {"motion_end_s": end, "free_vibration_s": stop - end, "decayed": not growth,
                       "grown": {c: g for c, g in growth}}


def _own_motion(deck, req: Request) -> GivenMotions:
    """The deck's own excitation.support, checked against the RRS."""
    from rbhyst.model.system import assemble

    system = assemble(deck, deck.base)
    duration = deck.analysis.duration or system.excitation.duration or 0.0
    own = _deck_trs(system.excitation, duration, req.rrs)
    strong = _deck_strong_motion(system.excitation, req.rrs)
    end = system.excitation.duration  # (None: a signal without end, the deck's own duration)
    given = GivenMotions([("deck", None, end)],
                         [{"number": 1, "source": "the deck's excitation.support",
                           "trs": {axis: c.summary() for axis, c in own.items()}, "strong_motion": strong}],
                         {axis: [("TRS, the deck's motion", c)] for axis, c in own.items()})
    given.band_ok = all(c.in_band for c in own.values())
    given.peak_ok = all(c.peak_ok for c in own.values())
    given.strong_ok = all(f is None or f["strong_motion_pass"] is not False for f in strong.values())
    return given


def _deck_strong_motion(excitation, rrs: dict[str, RRS]) -> dict:
    """Each axis's strong motion where its signal is a record (None for an analytic signal)."""
    from rbhyst.model.records import Series

    out = {}
    for axis, r in rrs.items():
        signal = getattr(excitation, "ag" + axis[1:])
        if not isinstance(signal, Series):
            out[axis] = None
            continue
        d = strong_motion.measured(np.asarray(signal.values, float), signal.dt)
        least = r.strong_min_s
        out[axis] = {**d, "strong_motion_s": d["bracketed_25_s"], "strong_motion_min_s": least,
                     "strong_motion_pass": None if least is None else d["bracketed_25_s"] >= least}
    return out


def _made_motions(deck, req: Request, folder: Path, notes: list) -> GivenMotions:
    """Spectrum-compatible motions made, written into ``folder`` (motions/, trs.csv,
    trs_fine.csv, records.csv, motions.json) and checked."""
    made = matching.make_motions(req.rrs, req.motions, req.duration, req.motion_dt, req.seed, vertical=req.vertical,
                                 table=req.table)
    (folder / "motions").mkdir()
    mark = f"# rbhyst qualify {deck.source.name if deck.source else 'deck'}"
    decks, checks = [], {axis: [] for axis in req.rrs}
    for m in made:
        files = {}
        for axis in m.records:
            files[axis] = folder / "motions" / matching.record_name(m, axis)
            files[axis].write_text(matching.record_text(m, axis, mark), encoding="utf-8")
            checks[axis].append((f"TRS, motion {m.number}", m.records[axis].check))
        decks.append((f"motion {m.number}", _support(files), m.duration))
    matching.write_tables(folder, made)
    summary = matching.motions_summary(made, req.rrs, req.standard)
    (folder / "motions.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    facts = [{**m, "files": {a: f"motions/{f}" for a, f in m["files"].items()}} for m in summary["motions"]]
    records = [r for m in made for r in m.records.values()]
    return GivenMotions(decks, facts, checks,
                        all(r.check.in_band for r in records) and
                        all(m.correlation is None or abs(m.correlation) < matching.MAX_CORRELATION for m in made),
                        all(r.check.peak_ok for r in records), all(r.strong_ok for r in records))


def qualification_inputs(deck, req: Request) -> list[tuple[str, Path, str]]:
    """The files a qualification reads: the deck, the RRS files asked for (the deck's or the
    command line's), the deck's records where its own motion is the test's, and its force files."""
    own = [i for i in deck_inputs(deck) if not i[0].startswith("qualify.")
           and (req.motions == "deck" or not i[0].startswith("excitation.support."))]
    first = [i for i in own if i[0] == "deck"]
    return first + req.files + [i for i in own if i[0] != "deck"]


def _deck_trs(excitation, duration: float, rrs: dict[str, RRS]) -> dict:
    """The TRS of the deck's own support motion per axis on the fine grid of the check range (the
    standard's points among it), from its signals (rbhyst.solve.ground)."""
    from rbhyst.analyses.qualification.rrs import fine_grid, standard_points
    from rbhyst.solve.ground import ground_spectra, signal_chunks
    from rbhyst.solve.located import rest_samples

    out = {}
    for axis, r in rrs.items():
        signal = getattr(excitation, "ag" + axis[1:])
        f = fine_grid(*r.check_range)
        points = standard_points(f, r.check_range)
        if signal is None:
            sa, peak = np.zeros(len(f)), 0.0
        else:
            periods = np.sort(1.0 / f)
            step = getattr(signal, "dt", periods[0] / 20.0)
            t_end = max(duration, signal.end or duration) + rest_samples(periods, [r.damping], step) * step
            sa = ground_spectra(type(excitation)(**{"ag" + axis[1:]: signal}), t_end, [r.damping],
                                periods).spectrum.sa[:, 0, 0]
            sa = sa[np.argsort(np.argsort(1.0 / f))]
            peak = 0.0  # the signal's peak acceleration, over its samples and the values it jumps to
            for _, values, jump in signal_chunks(signal, t_end, periods[-1]):
                peak = max(peak, float(np.max(np.abs(values), initial=0.0)), 0.0 if jump is None else abs(float(jump)))
        out[axis] = matching.Check(f[points], r(f[points]), sa[points], r.band, peak, r.peak_min, f, r(f), sa)
    return out


def used_statistic(asked: str, n: int) -> str:
    """The statistic the demand is: "mean" only where asked and from MEAN_FROM motions on."""
    return "mean" if asked == "mean" and n >= MEAN_FROM else "max"


def statistic_facts(asked: str, n: int) -> dict:
    """qualification.json's ``statistic``: asked, used, over how many motions, and its rule."""
    used = used_statistic(asked, n)
    motions = f"{n} motion{'s' * (n != 1)}"
    if used == "mean":
        rule = f"the mean over the {motions} (qualify.statistic = \"mean\": seven or more, ASCE 7-10 16.2.4)"
    elif asked == "mean":
        rule = (f"the largest over the {motions} (qualify.statistic = \"mean\" takes the mean from {MEAN_FROM} "
                "motions on, ASCE 7-10 16.2.4)")
    else:
        rule = f"the largest over the {motions}: each motion a test the equipment must pass"
    return {"asked": asked, "used": used, "motions": n, "rule": rule}


def _criterion(kind: str, item: str, unit: str, per_run: list[float], capacity: float, label: str,
               statistic: str, motions: list[str], **extra) -> dict:
    """A criterion's demand (the statistic over ``per_run``), capacity, margin and pass, and each
    motion's own demand and pass (``over_capacity``: the motions beyond it, whatever the statistic)."""
    demand = float(np.mean(per_run)) if statistic == "mean" else float(np.max(per_run))
    each = [bool(v <= capacity) for v in per_run]
    return {"criterion": kind, "item": item, "unit": unit, "demand": demand, "capacity": capacity,
            "margin": 1.0 - demand / capacity, "pass": bool(demand <= capacity), "per_motion": per_run,
            "per_motion_pass": each, "over_capacity": [m for m, ok in zip(motions, each) if not ok],
            **extra, "label": label}


def _criteria(deck, req: Request, runs: list[tuple[str, dict]]) -> list[dict]:
    """Every criterion's demand (from each run's summary, by the request's statistic), capacity,
    margin and pass, with each motion's."""
    out = []
    summaries = [s for _, s in runs]
    motions = [label for label, _ in runs]
    stat = used_statistic(req.statistic, len(runs))
    first = 1
    for i, (el, origin) in enumerate(deck.element_entries, start=1):
        span = f"e{first}" if el.count == 1 else f"e{first}-e{first + el.count - 1}"
        if el.stroke is not None:
            strokes = [s["elements"][i - 1]["stroke"] for s in summaries]
            use = [st["utilization"] for st in strokes]
            # the capacity is the limit on the side where the worst motion reached it; a motion
            # that peaked on the other side counts by its utilization of its own side
            k = int(np.argmax(use))
            up = strokes[k]["peak_deformation_m"] >= 0
            lo, hi = strokes[k]["limits_m"]
            capacity = hi if up else -lo
            peaks = [abs(st["peak_deformation_m"]) if (st["peak_deformation_m"] >= 0) == up else u * capacity
                     for st, u in zip(strokes, use)]
            out.append(_criterion("stroke", f"{origin.label} ({span})", "m", peaks, capacity,
                                  f"stroke {origin.label} ({span})", stat, motions,
                                  utilization=[float(u) for u in use], column=f"e{first}_u_m"))
        first += el.count
    directions = list(req.axes)  # x1, x2 (and x3 in space)
    for name, limit in (req.acceleration_limit_g or {}).items():
        limits = limit if isinstance(limit, list) else [limit] * len(directions)
        for j, direction in enumerate(directions):
            column = f"at{j + 1}_m_s2" if name == "G" else f"{name}_at{j + 1}_m_s2"
            per_run = [s["peaks"][column] / G for s in summaries]
            out.append(_criterion("acceleration", f"{name} {direction}", "g", per_run, float(limits[j]),
                                  f"acceleration {name} {direction}", stat, motions, column=column))
    caps = req.force_capacity_N
    if caps is not None:
        n_el = sum(el.count for el in deck.all_elements)
        named = caps if isinstance(caps, dict) else {f"e{k}": caps for k in range(1, n_el + 1)}
        for name in sorted(named, key=lambda e: int(e[1:])):
            column = f"{name}_f_N"
            per_run = [s["peaks"][column] for s in summaries]
            out.append(_criterion("force", name, "N", per_run, float(named[name]), f"force {name}", stat, motions,
                                  column=column))
    return out


def _accuracy(runs: list[tuple[str, dict]], warn_error: float) -> dict:
    """The worst estimated error over the runs and whether each can vouch for its figures."""
    per, ok = [], True
    for label, s in runs:
        acc = s.get("accuracy") or {}
        est = acc.get("estimated_error") or {}
        if not est:
            per.append({"motion": label, "estimated_error": None, "status": acc.get("status", "not estimated")})
            ok = False
            continue
        name, worst = max(est.items(), key=lambda kv: kv[1])
        good = worst <= warn_error and acc.get("status") != "sensitive"
        ok &= good
        per.append({"motion": label, "estimated_error": worst, "output": name, "status": acc.get("status"),
                    "pass": good})
    worst = max((p["estimated_error"] for p in per if p["estimated_error"] is not None), default=None)
    return {"pass": ok, "estimated_error": worst, "warn_error": warn_error, "per_motion": per,
            "rule": "every run's largest estimated error at most analysis.warn_error and not sensitive"}


def accuracy_lines(acc: dict) -> list[str]:
    """The line a verdict says where a run cannot vouch for its accuracy (``_accuracy``'s dict)."""
    if acc["pass"]:
        return []
    worst = acc["estimated_error"]
    return ["fail: a run cannot vouch for its accuracy: " +
            ("no error estimate" if worst is None else
             f"estimated error {100 * worst:.2g} % (at most {100 * acc['warn_error']:g} %)") +
            "; a smaller --dt or --tolerance, or no --integrator (rbhyst then chooses the step), would bring it within"]


def verdict_lines(v: Verdict) -> list[str]:
    """The console's account: each failed criterion, the least margin, and the verdict."""
    d = v.data
    lines = [f"note: {n}" for n in d["notes"]]
    used = d["statistic"]["used"]
    for c in v.criteria:
        several = len(c["per_motion"]) > 1
        over = [x for x, ok in zip(c["per_motion"], c["per_motion_pass"]) if not ok]
        each = (f"over {c['capacity']:.4g} {c['unit']} in {len(over)} of {len(c['per_motion'])} motions: "
                + ", ".join(f"{m} {x:.4g} {c['unit']}" for m, x in zip(c["over_capacity"], over))) if over else ""
        if not c["pass"]:
            lines.append(f"fail: {c['label']}: {c['demand']:.4g} {c['unit']} > {c['capacity']:.4g} {c['unit']}"
                         + (f" (the {used} over the motions; {each})" if several else ""))
        elif over and several:
            lines.append(f"note: {c['label']}: {each}; the {used}, the verdict's statistic, is within")
    # where every checked frequency's TRS is: trs.csv and trs_fine.csv of made motions; the deck's own motion's in
    # qualification.json (its lowest and highest) and qualification.png
    where = "trs.csv, trs_fine.csv" if any("files" in m for m in d["motions"]) else "qualification.json, qualification.png"
    if not d["trs"]["within_band"]:
        lines.append(f"fail: the motions' TRS is not within the RRS's band ({where})")
    if not d["trs"]["peak_pass"]:
        lines.append(f"fail: a motion's peak acceleration is below the least the RRS asks for ({where})")
    if not d["trs"].get("strong_motion_pass", True):
        lines.append("fail: a motion's strong motion is shorter than the RRS asks for (qualification.json, "
                     "motions.<k>.axes or .strong_motion)")
    acc = d["accuracy"]
    lines += accuracy_lines(acc)
    for w in d["warnings"]:
        lines.append(f"fail: warning: {w}")
    least = min(v.criteria, key=lambda c: c["margin"]) if v.criteria else None
    tail = f"; least margin {least['margin']:.3g} ({least['label']})" if least else ""
    est = acc["estimated_error"]
    lines.append(f"verdict: {'pass' if v.passed else 'fail'}: {len(v.criteria)} criteria, "
                 f"{sum(c['pass'] for c in v.criteria)} within capacity{tail}; "
                 f"estimated error {'not given' if est is None else f'{100 * est:.2g} %'}")
    return lines
