"""The command line: load -> assemble -> simulate -> write. Nothing below knows about the terminal."""

import gc
import os
import signal
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Optional

import typer

from rbhyst._version import __version__
from rbhyst.files import outdir
from rbhyst.errors import AnalysisError, InputError
from rbhyst.terminal import Command, Group, Progress

app = typer.Typer(
    cls=Group,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help texts hold units in brackets ("[s]"), not markup
    help="Nonlinear dynamics of rigid bodies, in the plane or in space, on Vaiana-Rosati hysteretic supports.",
)

EXIT_INPUT = 2  # the user's deck or data is wrong
EXIT_ANALYSIS = 3  # the analysis cannot give an answer it can vouch for


def say(msg: str) -> None:
    typer.echo(msg, err=True)


@contextmanager
def user_errors():
    """One line per problem on stderr, no traceback: exit 2 for input, 3 for numerics."""
    try:
        yield
    except InputError as err:
        for p in err.problems:
            say("error: " + p.replace("\r", "\\r").replace("\n", "\\n"))
        raise typer.Exit(EXIT_INPUT) from None
    except AnalysisError as err:
        say(f"error: {err}")
        raise typer.Exit(EXIT_ANALYSIS) from None


def say_replaced(target: Path, command: str) -> None:
    """A note before ``command`` writes into a folder holding another command's results, which
    it replaces (rbhyst run says so itself, deck by deck)."""
    from rbhyst.api import replaced_results

    for note in replaced_results(Path(target), command):
        say(f"note: {note}")


def command_line(ctx: typer.Context) -> str:
    """The command as run, quoted as a shell would need it to run it again (for the report)."""
    import shlex

    from rbhyst.terminal import ARGV

    return shlex.join(["rbhyst", *ctx.meta.get(ARGV, [])])


def _version(value: bool):
    if value:
        typer.echo(f"rbhyst {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[Optional[bool], typer.Option("--version", callback=_version, is_eager=True,
                                                    help="Print the version and exit.")] = None,
):
    pass


@app.command(cls=Command)
def run(
    ctx: typer.Context,
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck.")],
    out: Annotated[Optional[Path], typer.Option("--out", help="Output folder (default: the deck's).")] = None,
    integrator: Annotated[Optional[str], typer.Option(help="Override analysis.integrator.")] = None,
    dt: Annotated[Optional[float], typer.Option(help="Override analysis.dt [s].")] = None,
    tolerance: Annotated[Optional[float], typer.Option(
        help="The accuracy asked for (relative error of the body's motion: u1, u2, theta3 in 2-D): rbhyst chooses how to meet it.")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write PNG plots.")] = True,
    report: Annotated[bool, typer.Option("--report", help="Also write report.html (see `rbhyst report`).")] = False,
):
    """Time-history analysis of the deck: time_history.csv, summary.json and PNG plots."""
    import warnings

    from rbhyst import api
    from rbhyst.errors import RbhystWarning
    from rbhyst.solve.kernels import compiled as kernels
    from rbhyst.model.deck import ANALYSIS_SECTIONS

    monitor = Progress()
    try:
        with user_errors():
            d = api.load_deck(deck, need=ANALYSIS_SECTIONS)
            adaptive = (integrator or d.analysis.integrator) == "adaptive" or (
                tolerance if tolerance is not None else d.analysis.tolerance) is not None
            if not kernels.cached(kernels.run_kernels(adaptive)):
                say("note: compiling the numba kernels, once (a minute or two); later runs load them from the cache")
            target = out if out is not None else output_dir(d, deck)
            if report:
                from rbhyst.report.report_file import check_report_target

                check_report_target(target)
            with warnings.catch_warnings():  # (printed below as "warning: ..." lines: the API's are for Python)
                warnings.simplefilter("ignore", RbhystWarning)
                result = api.run(d, integrator=integrator, dt=dt, out=target, plots=plots and d.output.plots,
                                 tolerance=tolerance, monitor=monitor, command=command_line(ctx))
            if report:
                from rbhyst.report.report_file import write_report

                write_report(target)
    finally:
        monitor.close()
    for note in result.notes:  # after the run: a failing deck gets its error lines alone
        if note not in monitor.said:
            say(f"note: {note}")
    for warning in result.warnings:
        say(f"warning: {warning}")
    from rbhyst.report.console import element_table, mode_table, rang_lines, stop_lines

    summary = result.summary()
    for line in mode_table(summary["modes"]) + rang_lines(summary.get("rang")):  # what the body is, then what it did
        say(line)
    say(run_line(result))
    for line in element_table(summary) + stop_lines(summary):
        say(line)
    say(f"wrote {target}")


@app.command(cls=Command)
def modes(
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck ([body], [hysteresis] and [[elements]] suffice).")],
    as_json: Annotated[bool, typer.Option("--json", help="Print summary.json's modes as JSON instead of a table.")] = False,
    amplitude: Annotated[Optional[float], typer.Option(
        help="Every element at its effective (secant) stiffness on the steady cycle of this amplitude [m].")] = None,
    stiffness: Annotated[Optional[str], typer.Option(
        help="With --amplitude: secant (k_eff, the default) or reversal (the tangent just after a "
             "reversal of that cycle: small vibrations about it).")] = None,
):
    """Natural frequencies and mode shapes of the deck's body on its elements, without running it.

    Of the initial system (M, K0) and, when the deck gives body.gravity, of the elements' tangents
    at the static equilibrium under the weight; with --amplitude, of every element's stiffness on
    the steady cycle of that amplitude (as calibrate-plot --amplitudes writes to effective.csv).
    Undamped: dampers and Rayleigh damping do not change them. Written to stdout; nothing is
    written to disk.
    """
    from rbhyst import api

    with user_errors():
        try:
            found = api.modes(deck, amplitude=amplitude, stiffness=stiffness)
        except InputError as err:  # (the API's argument names are the command's options)
            raise InputError([p if not p.startswith(("amplitude:", "stiffness:")) else "--" + p
                              for p in err.problems]) from None
    if as_json:
        import json

        typer.echo(json.dumps(found, indent=2))
        return
    from rbhyst.report.console import mode_table

    for line in mode_table(found):
        typer.echo(line)


def _sweep_request(d, direction, amplitude, units, frequencies, f_from, f_to, count):
    """transmissibility's (amplitudes, frequencies), or an InputError with every problem of the
    command line at once: each option's, then the request's (in the units given)."""
    from rbhyst.analyses.transmissibility import directions, frequency_list, request_problems

    problems, amplitudes, freqs = [], [], []
    try:
        amplitudes = _split_list(amplitude, "--amplitude", float)
    except InputError as err:
        problems += err.problems
    try:
        freqs = frequency_list(_split_list(frequencies, "--frequencies", float), f_from, f_to, count)
    except InputError as err:
        problems += err.problems
    said = {p.split(":")[0] for p in problems}  # (what failed above is said once)
    problems += [p for p in request_problems(direction, amplitudes or [1.0], freqs or [1.0], directions(d))
                 if p.split(":")[0] not in said]
    if units not in ("g", "m/s2"):
        problems.append(f"--units: {units!r}: g or m/s2")
    if problems:
        raise InputError(problems)
    return amplitudes, freqs


def run_line(result) -> str:
    """The console's one line on a run: method, steps, time, peak displacements and accelerations."""
    from rbhyst.model.deck import ACCEL_UNITS

    e, s = result.extremes, result.settings
    g = ACCEL_UNITS["g"]
    coords = result.system.coordinates
    rest = set(result.at_rest())  # (rounding, printed as 0)

    def peak(column: str) -> float:
        return 0.0 if column in rest else e.peak(column)

    at = ", ".join(f"|{c.key('at')}| = {peak(c.column('at')):.4g} m/s2 ({peak(c.column('at')) / g:.3g} g)"
                   for c in coords if not c.rotation)
    method = s.integrator + (f" (rtol {s.rtol:g})" if s.integrator == "adaptive" else "")
    motion = ", ".join(f"|{c.key('d')}| = {peak(c.column('d')):.4g} {c.d[1]}" for c in coords)
    chosen = result.chosen
    steps = f"{result.steps} steps"
    if chosen is not None and s.integrator != "adaptive" and s.refine > 1:
        step = f"dt = {s.dt:g} s, compute step {chosen['compute_step_s']:.3g} s (chosen for the accuracy)"
        steps = f"{result.stats.steps_taken} compute steps"
    else:
        step = f"dt = {s.dt:g} s"
    kin = ", exact kinematics" if result.system.kinematics == "exact" else ""
    line = f"{method}{kin}, {step}, {steps} in {result.wall_s:.3g} s; peaks {motion}, {at}"
    acc = result.accuracy
    if acc and acc.get("estimated_error"):
        name, worst = max(acc["estimated_error"].items(), key=lambda kv: kv[1])
        line += f"; estimated error {100 * worst:.2g} % ({name}{', sensitive' if acc['status'] == 'sensitive' else ''}, " \
                f"{acc['wall_s']:.2g} s to estimate)"
    else:  # an answer always says how far it can be trusted, even when that is "not said"
        line += "; error not estimated" + (f" ({acc['status']})" if acc else " (analysis.estimate_error = false)")
    return line


@app.command("calibrate-plot", cls=Command)
def calibrate_plot(
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck with hysteresis sets (and optionally a loops table).")],
    sets: Annotated[Optional[list[str]], typer.Option("--set", help="Only this set (repeatable; default: all).")] = None,
    data: Annotated[Optional[Path], typer.Option(
        help="Measured loop (CSV, displacement and force columns with units in the header): "
             "impose its displacement history and report the fit.")] = None,
    u_units: Annotated[Optional[str], typer.Option(help="Displacement units of --data (m, cm, mm, ...).")] = None,
    f_units: Annotated[Optional[str], typer.Option(help="Force units of --data (N, kN, ...).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: results/<deck stem>-loops/ beside the deck).")] = None,
    amplitudes: Annotated[Optional[str], typer.Option(
        help="Also write effective.csv: each set's effective stiffness and damping on its steady "
             "cycle of each of these amplitudes [m], comma-separated.")] = None,
):
    """Force-displacement loops of VRM sets: loops.png, loops_<set>.csv, summary.json (fit.json with
    --data; effective.csv with --amplitudes)."""
    from rbhyst.analyses.calibration import (effective_rows, header, loop_result, protocol, safe_names, write_effective_csv,
                                             write_json, write_loop_csv)
    from rbhyst.model.deck import load_deck
    from rbhyst.files.outdir import staged_directory
    from rbhyst.model.testdata import read_loop_data

    with user_errors():
        d = load_deck(deck)  # the sets (and [loops]) are enough
        names = _chosen_sets(deck, d, sets)
        amps = _amplitudes(amplitudes)
        effective = None if amps is None else effective_rows({n: d.hysteresis[n].array() for n in names}, amps)
        if data is not None:
            measured = read_loop_data(data, u_units, f_units)
            u, f_data = measured.u, measured.f
        else:
            if u_units is not None or f_units is not None:
                raise InputError("--u-units/--f-units: only with --data")
            measured, f_data = None, None
            _, u = protocol(d.loops)
        results = [loop_result(n, d.hysteresis[n].array(), u, f_data) for n in names]
        summary = {**header("calibrate-plot"), "deck": deck.name,
                   "data": None if measured is None else measured.name,
                   "protocol": None if measured is not None else (d.loops.model_dump() if d.loops else "default"),
                   "sets": {r.name: r.summary() for r in results}}
        target = out if out is not None else deck.parent / "results" / f"{deck.stem}-loops"
        say_replaced(target, "calibrate-plot")
        files = safe_names(names)
        with staged_directory(target) as tmp:
            for r in results:
                write_loop_csv(r, tmp / f"loops_{files[r.name]}.csv")
            if effective is not None:
                summary["effective"] = effective
                write_effective_csv(effective, tmp / "effective.csv")
            write_json(summary, tmp / "summary.json")
            if measured is not None:
                write_json({**header("calibrate-plot"), "deck": deck.name, "data": measured.name,
                            "sets": {r.name: {"nrmse": r.nrmse, "r2": r.r2,
                                              "hysteretic_work_J": float(r.work[-1]),
                                              "dissipated_per_cycle_J": r.dissipated} for r in results}},
                           tmp / "fit.json")
            from rbhyst.report.loops import plot_loops

            plot_loops(results, tmp / "loops.png", title=d.title)
    for r in results:
        fit = f"NRMSE {r.nrmse:.3%}, R^2 {r.r2:.5f}; " if r.f_data is not None else ""
        ed = r.dissipated
        cyc = f"{len(ed)} closed cycle{'s' if len(ed) != 1 else ''}, last dissipates {ed[-1]:.6g} J" if ed \
            else "no closed cycle"
        say(f"{r.name}: {fit}hysteretic work {r.work[-1]:.6g} J, {cyc}")
    for row in effective or ():
        say(f"{row['set']} at {row['amplitude_m']:g} m: k_eff {row['k_eff_N_m']:.5g} N/m, "
            f"beta_eff {row['beta_eff']:.4f}, {row['energy_J']:.5g} J per cycle")
    say(f"wrote {target}")


def _amplitudes(text: str | None) -> list[float] | None:
    """--amplitudes as a list of positive floats [m], or InputError naming every bad one."""
    amps = _split_list(text, "--amplitudes", float)
    if amps is None:
        return None
    bad = [a for a in amps if not a > 0.0]
    if not amps or bad:
        raise InputError(f"--amplitudes: {text!r}: displacement amplitudes > 0 in m, comma-separated")
    return amps


@app.command(cls=Command)
def calibrate(
    data: Annotated[Optional[Path], typer.Argument(
        help="Measured loop: CSV with displacement and force columns, units in the header (or --catalogue).")] = None,
    set_name: Annotated[str, typer.Option("--set", help="The set to identify (its name in --init).")] = ...,
    init: Annotated[Path, typer.Option(help="Deck holding the starting values of the set.")] = ...,
    catalogue: Annotated[Optional[Path], typer.Option(
        help="Instead of a measured loop: a catalogue CSV, columns amplitude_m, k_eff_N_m, beta_eff (and optionally "
             "force_N, a static point): a symmetric set matching each row's effective stiffness and damping.")] = None,
    free: Annotated[Optional[list[str]], typer.Option(
        help="Parameters to fit (repeatable or comma-separated): loading.kb, kb+, kb- or kb for both "
             "branches. Default: all 16. With --catalogue: kb, f0, alpha, beta1, ... without a branch "
             "(the set stays symmetric), default kb,f0,alpha.")] = None,
    fix: Annotated[Optional[list[str]], typer.Option(help="Parameters to keep at their --init values.")] = None,
    starts: Annotated[int, typer.Option(min=1, help="Number of starts (the first is --init).")] = 6,
    seed: Annotated[int, typer.Option(help="Random seed for the extra starts.")] = 0,
    u_units: Annotated[Optional[str], typer.Option(help="Displacement units if the header has none.")] = None,
    f_units: Annotated[Optional[str], typer.Option(help="Force units if the header has none.")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: results/<data stem>-calibrate/ beside the data).")] = None,
):
    """Identify a VRM set from measured loops (or a catalogue): fitted.toml (deck fragment), fit.json, loops.png."""
    if (data is None) == (catalogue is None):
        with user_errors():
            raise InputError("calibrate: a measured loop (DATA) or --catalogue FILE.csv, not both" if data is not None
                             else "calibrate: give a measured loop (DATA) or --catalogue FILE.csv")
    if catalogue is not None:
        with user_errors():
            if u_units is not None or f_units is not None:
                raise InputError("--u-units/--f-units: not with --catalogue (its columns are in m and N)")
        _calibrate_catalogue(catalogue, set_name, init, free, fix, starts, seed, out)
        return
    _calibrate_loop(data, set_name, init, free, fix, starts, seed, u_units, f_units, out)


#: NRMSE above which ``calibrate`` warns that the fit does not follow the data
POOR_FIT_NRMSE = 0.05


def _calibrate_loop(data: Path, set_name: str, init: Path, free, fix, starts: int, seed: int, u_units, f_units,
                    out) -> None:
    """calibrate DATA: the set fitted to a measured loop (rbhyst.analyses.calibration.fit_set)."""
    import tomllib

    from rbhyst.analyses.calibration import (NAMES, check_orientation, deck_fragment, fit_set, header, loop_result, parameters_dict, parse_names, round_set, safe_names, write_json, write_loop_csv)
    from rbhyst.model.deck import load_deck, parse_deck
    from rbhyst.files.outdir import staged_directory
    from rbhyst.model.testdata import read_loop_data

    with user_errors():
        d = load_deck(init)
        _chosen_sets(init, d, [set_name])
        measured = read_loop_data(data, u_units, f_units)
        check_orientation(measured.u, measured.f, str(data))
        chosen = parse_names(free, "--free") if free else list(range(16))
        fixed = parse_names(fix, "--fix") if fix else []
        chosen = [i for i in chosen if i not in fixed]
        p0 = d.hysteresis[set_name].array()
        fit = fit_set(p0, measured.u, measured.f, chosen, starts=starts, seed=seed)
        p = fit.p = round_set(fit.p)  # what fitted.toml holds: every number reported is for it
        res = loop_result(set_name, p, measured.u, measured.f)
        fragment = deck_fragment(
            set_name, p,
            f"VRM set fitted by rbhyst calibrate to {measured.name} ({measured.u.size} samples):\n"
            f"NRMSE {res.nrmse:.3%}, R^2 {res.r2:.5f}. Paste into a deck as it is.")
        try:
            parse_deck(tomllib.loads(fragment))
        except InputError as err:
            raise AnalysisError(f"calibration failed: the fitted set is not a valid deck set: {err.problems[0]}") \
                from None
        report = {
            **header("calibrate"), "data": measured.name, "data_units": [measured.u_units, measured.f_units],
            "samples": int(measured.u.size), "init": init.name, "set": set_name,
            "free": [NAMES[i] for i in fit.free], "starts": starts, "seed": seed,
            "parameters": parameters_dict(p),
            "nrmse": res.nrmse, "r2": res.r2, "iterations": fit.njev, "function_evaluations": fit.nfev,
            "status": fit.status, "message": fit.message, "wall_s": fit.wall_s,
            "parameter_table": fit.parameters(),
            "hysteretic_work_J": float(res.work[-1]), "dissipated_per_cycle_J": res.dissipated,
            "cycles": [c.as_dict() for c in res.cycles],
            "start_log": fit.starts,
        }
        target = out if out is not None else data.parent / "results" / f"{data.stem}-calibrate"
        say_replaced(target, "calibrate")
        with staged_directory(target) as tmp:
            (tmp / "fitted.toml").write_text(fragment, encoding="utf-8")
            write_json(report, tmp / "fit.json")
            write_loop_csv(res, tmp / f"loops_{safe_names([set_name])[set_name]}.csv")
            from rbhyst.report.loops import plot_loops

            plot_loops([res], tmp / "loops.png", initial={set_name: p0},
                       title=f"{set_name} fitted to {measured.name}")
    undetermined = [r["name"] for r in fit.parameters() if r["free"] and not r["determined"]]
    say(f"{set_name}: NRMSE {res.nrmse:.3%}, R^2 {res.r2:.5f}; {len(fit.free)} free parameters, "
        f"{fit.njev} iterations, {len(fit.starts)} starts in {fit.wall_s:.3g} s")
    if undetermined:
        say(f"note: the data do not pin down (standard error > 10% or at a bound): {', '.join(undetermined)}")
    if fit.status == 0:
        say("note: the best start stopped at the evaluation limit; more --starts may help")
    if res.nrmse > POOR_FIT_NRMSE:
        say(f"warning: NRMSE {res.nrmse:.1%} is above {POOR_FIT_NRMSE:.0%}: the set does not follow the data; "
            "look at loops.png, try another --init or free more parameters")
    say(f"wrote {target}")


def _calibrate_catalogue(path: Path, set_name: str, init: Path, free, fix, starts: int, seed: int, out) -> None:
    """calibrate --catalogue: the symmetric set matching the catalogue's rows (rbhyst.analyses.catalogue):
    fitted.toml, fit.json, effective.csv of the fitted set, loops.png against the catalogue."""
    import tomllib

    from rbhyst.analyses.calibration import deck_fragment, header, parameters_dict, round_set, write_effective_csv, write_json
    from rbhyst.analyses.catalogue import (DEFAULT_FREE, MATCHED, compare, fit_catalogue, parse_free, read_catalogue)
    from rbhyst.files.outdir import staged_directory
    from rbhyst.model.deck import load_deck, parse_deck

    with user_errors():
        d = load_deck(init)
        _chosen_sets(init, d, [set_name])
        cat = read_catalogue(path)
        chosen = parse_free(free) if free else list(DEFAULT_FREE)
        fixed = parse_free(fix) if fix else []
        chosen = [n for n in chosen if n not in fixed]
        if not chosen:
            raise InputError("--free: no parameter left to fit")
        p0 = d.hysteresis[set_name].array()
        fit = fit_catalogue(p0, cat, chosen, starts=starts, seed=seed)
        p = round_set(fit.p)  # what fitted.toml holds: every number reported is for it
        rows = compare(p, cat)
        worst = max(abs(v["misfit"]) for r in rows for v in r.values() if isinstance(v, dict))
        fragment = deck_fragment(set_name, p, f"symmetric VRM set fitted by rbhyst calibrate to the catalogue "
                                 f"{cat.name} ({len(cat.rows)} rows):\nlargest misfit {worst:.3%}. Paste into a deck as it is.")
        try:
            parse_deck(tomllib.loads(fragment))
        except InputError as err:
            raise AnalysisError(f"calibration failed: the fitted set is not a valid deck set: {err.problems[0]}") \
                from None
        report = {**header("calibrate"), "catalogue": cat.name, "init": init.name, "set": set_name,
                  "free": fit.free, "starts": starts, "seed": seed, "parameters": parameters_dict(p),
                  "largest_misfit": worst, "matched_within": MATCHED, "rows": rows,
                  "function_evaluations": fit.nfev, "start_log": fit.starts}
        effective = [{"set": set_name, "amplitude_m": r["amplitude_m"], "k_eff_N_m": r["k_eff_N_m"]["set"],
                      "beta_eff": r["beta_eff"]["set"], "energy_J": r["energy_J"]} for r in rows if "k_eff_N_m" in r]
        target = out if out is not None else path.parent / "results" / f"{path.stem}-calibrate"
        with staged_directory(target) as tmp:
            (tmp / "fitted.toml").write_text(fragment, encoding="utf-8")
            write_json(report, tmp / "fit.json")
            write_effective_csv(effective, tmp / "effective.csv")
            from rbhyst.report.loops import plot_catalogue

            plot_catalogue(set_name, p, cat, tmp / "loops.png", title=f"{set_name} fitted to {cat.name}")
    for r in rows:
        said = ", ".join(f"{k} {v['set']:.5g} ({v['misfit']:+.2%})" for k, v in r.items() if isinstance(v, dict))
        say(f"{set_name} at {r['amplitude_m']:g} m: {said}")
    say(f"{set_name}: largest misfit {worst:.3%} with {', '.join(fit.free)} free, {len(fit.starts)} starts")
    if worst > MATCHED:
        say(f"warning: the symmetric set misses the catalogue by {worst:.1%} (more than {MATCHED:.0%}) at worst; "
            "look at loops.png, free more parameters (--free kb,f0,alpha,beta1,beta2) or try another --init")
    say(f"wrote {target}")


def _chosen_sets(deck_path: Path, deck, names: list[str] | None) -> list[str]:
    """The --set names (all sets when none), or InputError naming the unknown ones."""
    if not names:
        return list(deck.hysteresis)
    unknown = [n for n in names if n not in deck.hysteresis]
    if unknown:
        raise InputError(f"{deck_path}: --set {', '.join(repr(n) for n in unknown)}: no such set; "
                         f"defined: {', '.join(deck.hysteresis)}")
    return list(dict.fromkeys(names))


def _split_list(text: str | None, what: str, convert=str) -> list | None:
    if text is None:
        return None
    out = []
    for tok in (t.strip() for t in text.split(",")):
        if not tok:
            continue
        try:
            out.append(convert(tok))
        except ValueError:
            raise InputError(f"{what}: {tok!r} is not a number") from None
    return out


@app.command(cls=Command)
def study(
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck.")],
    integrators: Annotated[Optional[str], typer.Option(
        "--integrators", help="Comma-separated integrators (default: every fixed-step one).")] = None,
    dt: Annotated[Optional[str], typer.Option(
        "--dt", help="Comma-separated time steps [s] (default: 4, 2, 1, 1/2, 1/4, 1/8 x the deck's dt).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: the deck's output folder + '-study').")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write PNG plots.")] = True,
):
    """Accuracy against cost: each integrator at each dt against a reference solution.

    Writes study.csv (one row per run), study.json (observed orders, the reference's
    settings) and error_vs_runtime.png / error_vs_dt.png.
    """
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from rbhyst.model.deck import load_deck
    from rbhyst.model.system import assemble
    from rbhyst.files.outdir import staged_directory
    from rbhyst.solve.plan import grid, settings_from_deck
    from rbhyst.analyses.study import check_dts, check_integrators, fixed_step_names, run_study, write_csv, write_json

    with user_errors():
        d = load_deck(deck)
        settings = settings_from_deck(d)
        names = _split_list(integrators, "--integrators")
        names = check_integrators(names if names is not None else fixed_step_names())
        dts = _split_list(dt, "--dt", float)
        system = assemble(d, deck.parent)
        if dts is not None:
            n_steps, _ = grid(system, settings)
            check_dts(dts, n_steps * settings.dt)
        console = Console(stderr=True)
        columns = (TextColumn("{task.description:<40}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                   TimeElapsedColumn())
        with Progress(*columns, console=console, transient=True, disable=not console.is_terminal) as bar:
            task = bar.add_task("study", total=None)

            def progress(label: str, done: int, total: int) -> None:
                bar.update(task, description=label, completed=done, total=total)

            result = run_study(system, settings, names, dts, progress=progress)
        target = out if out is not None else _sibling_dir(d, deck, "-study")
        say_replaced(target, "study")
        with staged_directory(target) as tmp:
            write_csv(result, tmp / "study.csv")
            write_json(result, tmp / "study.json")
            if plots and d.output.plots:
                from rbhyst.report.study import write_plots

                write_plots(result, tmp)
    for note in system.notes:
        say(f"note: {note}")
    ref = result.reference
    say(f"reference: DOP853, rtol {ref['rtol']:g}: {ref['steps']} steps, {ref['reversals']} reversals "
        f"in {ref['wall_s']:.3g} s")
    for name in result.integrators:
        order = result.orders[name].get("order")
        at_deck = [r for r in result.runs if r.integrator == name and abs(r.dt - settings.dt) <= 1e-12 * settings.dt]
        where = ""
        if at_deck and at_deck[0].failed is None:
            where = f"; at dt = {settings.dt:g} s: error {at_deck[0].err_max:.3g} in {at_deck[0].wall_s:.3g} s"
        failed = sum(r.failed is not None for r in result.runs if r.integrator == name)
        say(f"{name}: observed order {'n/a' if order is None else f'{order:.2f}'}{where}"
            + (f"; {failed} run(s) failed (see study.json)" if failed else ""))
    say(f"wrote {target}")


@app.command(cls=Command)
def sweep(
    sweep_file: Annotated[Path, typer.Argument(metavar="SWEEP", help="TOML or YAML sweep file.")],
    workers: Annotated[Optional[int], typer.Option(
        "--workers", help="Local worker processes (default: the cores).")] = None,
    scheduler: Annotated[Optional[str], typer.Option(
        "--scheduler", help="Run on this Dask scheduler instead, e.g. tcp://host:8786 (tls:// with --tls-*).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: results/<sweep stem>/ beside the sweep file).")] = None,
    fresh: Annotated[bool, typer.Option("--fresh", help="Start over: forget the cases the folder holds.")] = False,
    save_histories: Annotated[bool, typer.Option(
        "--save-histories", help="Every case's time history into histories.parquet (needs pyarrow).")] = False,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write PNG plots.")] = True,
    report: Annotated[bool, typer.Option("--report", help="Also write report.html (see `rbhyst report`).")] = False,
    redraw: Annotated[bool, typer.Option(
        "--redraw", help="Write the tables and figures again even where they stand for the finished cases.")] = False,
    tls_ca_file: Annotated[Optional[Path], typer.Option(
        "--tls-ca-file", help="With a tls:// --scheduler: the CA certificate (PEM) the scheduler's is signed by.")] = None,
    tls_cert: Annotated[Optional[Path], typer.Option(
        "--tls-cert", help="With a tls:// --scheduler: this client's certificate (PEM).")] = None,
    tls_key: Annotated[Optional[Path], typer.Option(
        "--tls-key", help="With a tls:// --scheduler: this client's private key (PEM), if not in --tls-cert.")] = None,
):
    """One deck over motions x scale x deck values: cases.csv, stats.csv, sweep.json, plots.

    Finished cases are kept as they come: the same command after an interruption computes
    only what is missing.

    Long because the progress bar's callbacks close over the command's own state.
    """
    import time

    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from rbhyst.solve.kernels import compiled as kernels
    from rbhyst.sweep import SweepIncomplete, load_sweep, run_sweep

    began = time.perf_counter()  # the command's own time, the tables and figures included
    with user_errors():
        sw = load_sweep(sweep_file)
        target = out if out is not None else sw.default_out()
        say_replaced(target, "sweep")
        if report:
            from rbhyst.report.report_file import check_report_target

            check_report_target(target)
        from rbhyst.solve.kernels.compiled import ahead_of_time

        on_dask = scheduler is not None or (workers is None and getattr(sw.cluster, "scheduler", None) is not None)
        if on_dask:
            _quiet_dask()
        # built at install, the kernels need no compiling (and numba's cache stays empty)
        if not on_dask and not ahead_of_time() and not kernels.cached([_run_chunk()]):
            say("note: compiling the numba kernels, once (a minute or two); the workers load them from the cache")
            from rbhyst.api import run as _run

            _run(sw.short_deck())
        console = Console(stderr=True)
        columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                   TextColumn("{task.fields[failed]} failed"), TextColumn("{task.fields[rate]}"),
                   TimeElapsedColumn(), TimeRemainingColumn())
        t0 = [time.perf_counter()]
        with Progress(*columns, console=console, transient=True, disable=not console.is_terminal) as bar:
            task = bar.add_task("sweep", total=None, failed=0, rate="", visible=False)

            def progress(done: int, failed: int, total: int) -> None:
                dt = time.perf_counter() - t0[0]
                rate = f"{done / dt:.3g} cases/s" if done and dt > 0 else ""
                bar.update(task, completed=done, total=total, failed=failed, rate=rate, visible=True)

            def started(outcome, todo: int) -> None:
                n, m, k = len(sw.cases), len(sw.motions), len(sw.levels)
                axes = f"{m} motion{'s' * (m != 1)} x {k} scale level{'s' * (k != 1)}" + \
                    "".join(f" x {key}" for key in sw.vary_keys)
                work = f"computing {todo} on {outcome.where}" if todo else "nothing to compute"
                lines = [f"note: {note}" for note in outcome.notes]
                lines.append(f"sweep: {n} case{'s' * (n != 1)} ({axes}): {outcome.reused} in {target}, {work}")
                for line in lines:
                    if console.is_terminal:  # above the live bar
                        console.print(line, markup=False, highlight=False, soft_wrap=True)
                    else:
                        say(line)
                t0[0] = time.perf_counter()

            try:
                outcome = run_sweep(sw, out=target, workers=workers, scheduler=scheduler, fresh=fresh,
                                    save_histories=save_histories, plots=plots, progress=progress,
                                    started=started, tls_ca_file=tls_ca_file, tls_cert=tls_cert, tls_key=tls_key,
                                    redraw=redraw)
            except SweepIncomplete as err:
                say(f"error: {err}")
                raise typer.Exit(EXIT_ANALYSIS) from None
            except Interrupted as exc:
                from rbhyst.analyses.sweep.store import FOLDER

                say(f"interrupted: the finished cases are kept in {target / FOLDER}; "
                    "the same command computes the rest")
                outdir.received.clear()
                raise typer.Exit(128 + exc.signum) from None
        if report:
            from rbhyst.report.report_file import write_report

            write_report(target)
    failed = outcome.failed
    took = time.perf_counter() - began
    spent = f"{took:.3g} s" if took < 1000 else f"{took:.0f} s ({took / 60:.0f} min)"  # (not 3e+03 s)
    say(f"{outcome.ok} ok, {failed} failed; computed {outcome.computed}"
        + (f" on {outcome.where}" if outcome.computed else "")
        + f", {outcome.reused} already in the folder; {spent} in all")
    if failed:
        header, rows = outcome.case_rows()
        i_status, i_msg = header.index("status"), header.index("message")
        bad = [r for r in rows if r[i_status] == "failed"]
        for r in bad[:5]:
            say(f"warning: case {r[0]} ({r[1]}, scale {r[2]}) failed: {r[i_msg]}")
        if len(bad) > 5:
            say(f"warning: ... and {len(bad) - 5} more failed cases: see cases.csv (status, message)")
    if outcome.written:
        say(f"wrote {target}")
    else:
        say(f"{target}: its tables and figures stand for these cases, newer than their store (--redraw writes "
            "them again)")
    if outcome.killed:
        n = len(outcome.killed)
        say(f"error: the sweep is incomplete: case{'s' * (n != 1)} {', '.join(map(str, outcome.killed))} killed "
            f"{'their' if n != 1 else 'its'} worker process every time (failed in cases.csv, not kept): the same "
            f"command tries {'them' if n != 1 else 'it'} again, with more memory per worker if that was the cause")
        raise typer.Exit(EXIT_ANALYSIS)


def _run_chunk():
    """The compiled loop's function (numba's import: only where the kernels may need compiling)."""
    from rbhyst.solve.kernels.loop import run_chunk

    return run_chunk


def _quiet_dask() -> None:
    """Dask's own log lines off the console: the command says in its own lines what went wrong
    (the workers keep their logs)."""
    import logging

    try:
        import distributed  # noqa: F401  (it sets up its loggers when imported)
    except ImportError:
        return
    for name in ("distributed", "tornado", "bokeh"):
        for handler in logging.getLogger(name).handlers:
            handler.setLevel(logging.CRITICAL + 1)


@app.command(cls=Command)
def report(
    folder: Annotated[Path, typer.Argument(metavar="OUT_FOLDER",
                                           help="A folder rbhyst run, rbhyst sweep or rbhyst qualify wrote.")],
):
    """One self-contained report.html of a run's, a sweep's or a qualification's results (figures
    embedded), to send and print.

    It is added to the folder's files: the command's own stay as they are.
    """
    from rbhyst.report.report_file import write_report

    with user_errors():
        path = write_report(folder)
    say(f"wrote {path}")


@app.command(cls=Command)
def spectrum(
    record: Annotated[Path, typer.Argument(help="Support acceleration record: PEER .AT2, time,value table, "
                                                 "or one column with --dt.")],
    units: Annotated[str, typer.Option(help="Units of the record's values: g, m/s2 or cm/s2 (held to what the "
                                            "file declares).")],
    dt: Annotated[Optional[float], typer.Option(help="Sample step [s] of a one-column record.")] = None,
    kind: Annotated[str, typer.Option(help="rs: response spectra against period (spectra.csv); srs: the shock "
                                           "response spectrum against frequency (srs.csv, srs.png, pvss.png).")] = "rs",
    damping: Annotated[Optional[str], typer.Option(help="Comma-separated damping ratios (--kind rs; default "
                                                        "0.05).")] = None,
    periods: Annotated[Optional[str], typer.Option(
        help="Comma-separated periods [s] (--kind rs; default: 100 log-spaced from 0.01 to 10 s).")] = None,
    q: Annotated[Optional[str], typer.Option("--q", help="Comma-separated quality factors Q = 1 / (2 damping) "
                                                         "(--kind srs; default 10).")] = None,
    frequencies: Annotated[Optional[str], typer.Option(
        help="F1..F2 [Hz] (--kind srs; default 1 Hz to the lesser of 10 kHz and a tenth of the sample rate).")] = None,
    per_octave: Annotated[Optional[int], typer.Option(help="Frequencies an octave (--kind srs; default 12).")] = None,
    direction: Annotated[str, typer.Option(help="The direction the rows are labelled with (x1 or x2).")] = "x1",
    free_vibration: Annotated[bool, typer.Option(
        "--free-vibration/--no-free-vibration",
        help="Follow the record with rest until every oscillator has passed its peak.")] = True,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: results/<record stem>-spectrum/ beside the record).")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write spectra.png (srs.png, pvss.png).")] = True,
):
    """Response spectra of a support acceleration record: spectra.csv and spectra.png, or with
    --kind srs its shock response spectrum: srs.csv, srs.png and pvss.png."""
    from rbhyst.files.outdir import staged_directory

    with user_errors():
        if kind not in ("rs", "srs"):
            raise InputError(f"--kind: {kind!r}: rs (response spectra against period) or srs (the shock response "
                             "spectrum against frequency)")
        asked = {"--damping": damping, "--periods": periods, "--q": q, "--frequencies": frequencies,
                 "--per-octave": per_octave}
        other = ("--q", "--frequencies", "--per-octave") if kind == "rs" else ("--damping", "--periods")
        wrong = [f"{k}: not with --kind {kind}" for k in other if asked[k] is not None]
        if kind == "srs" and not free_vibration:
            wrong.append("--no-free-vibration: not with --kind srs (its residual spectrum is the free vibration)")
        if wrong:
            raise InputError(wrong)
        target = out if out is not None else record.parent / "results" / f"{record.stem}-spectrum"
        if kind == "srs":
            return _shock_spectrum(record, units, dt, q, frequencies, per_octave, target, plots)
        from rbhyst.results.writers import write_spectra_csv
        from rbhyst.analyses.record_spectrum import record_spectrum

        spectra = record_spectrum(record, units, dt=dt, dampings=_split_list(damping or "0.05", "--damping", float),
                                  periods=_split_list(periods, "--periods", float), direction=direction,
                                  free_vibration=free_vibration)
        say_replaced(target, "spectrum")
        with staged_directory(target) as tmp:
            write_spectra_csv(spectra, tmp / "spectra.csv")
            if plots:
                from rbhyst.report.spectra import plot_spectra

                plot_spectra(spectra, tmp / "spectra.png", title=record.name)
    s = spectra.spectrum
    for j, zeta in enumerate(s.dampings):
        i = int(s.sa[:, j, 0].argmax())
        say(f"damping {zeta:g}: peak sa {s.sa[i, j, 0]:.4g} m/s2 at T = {s.periods[i]:.4g} s; "
            f"sd {s.sd[:, j, 0].max():.4g} m at most")
    say(f"wrote {target}")


def _frequency_range(text: str | None) -> tuple[float, float] | None:
    """--frequencies F1..F2 as two numbers (Hz)."""
    if text is None:
        return None
    parts = text.split("..")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        raise InputError(f"--frequencies: {text!r}: F1..F2, two frequencies in Hz (e.g. 10..2000)") from None
    return lo, hi


def _shock_spectrum(record: Path, units: str, dt, q, frequencies, per_octave, target: Path, plots: bool) -> None:
    """``rbhyst spectrum --kind srs``: srs.csv, srs.png and pvss.png."""
    from rbhyst.analyses.record_spectrum import record_shock_spectrum
    from rbhyst.files.outdir import staged_directory
    from rbhyst.results.writers import write_srs_csv

    srs = record_shock_spectrum(record, units, dt=dt, qs=_split_list(q or "10", "--q", float),
                                frequencies=_frequency_range(frequencies),
                                per_octave=12 if per_octave is None else per_octave)
    with staged_directory(target) as tmp:
        write_srs_csv(srs, tmp / "srs.csv")
        if plots:
            from rbhyst.report.shock_spectra import plot_pvss, plot_srs

            plot_srs(srs, tmp / "srs.png", title=record.name)
            plot_pvss(srs, tmp / "pvss.png", title=record.name)
    f = srs.frequencies_hz
    for j, qj in enumerate(srs.qs):
        i = int(srs.maximax[:, j].argmax())
        k = int(srs.pv[:, j].argmax())
        say(f"Q {qj:g}: maximax {srs.maximax[i, j] / 9.80665:.4g} g at {f[i]:.4g} Hz; pseudo-velocity "
            f"{srs.pv[k, j]:.4g} m/s at most ({f[k]:.4g} Hz); {len(f)} frequencies {f[0]:.4g}-{f[-1]:.4g} Hz")
    say(f"wrote {target}")


@app.command(cls=Command)
def transmissibility(
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck (its excitation is replaced by the sine).")],
    direction: Annotated[str, typer.Option(help="Direction of the support's sine: x1 or x2 (x1, x2 or x3, the "
                                                "vertical, for a deck in space).")],
    amplitude: Annotated[str, typer.Option(help="Amplitude(s) of the support acceleration, comma-separated, "
                                                "in --units.")],
    units: Annotated[str, typer.Option(help="Units of --amplitude: g or m/s2.")],
    frequencies: Annotated[Optional[str], typer.Option(help="Comma-separated frequencies [Hz].")] = None,
    f_from: Annotated[Optional[float], typer.Option("--from", help="Lowest frequency [Hz] (log-spaced).")] = None,
    f_to: Annotated[Optional[float], typer.Option("--to", help="Highest frequency [Hz].")] = None,
    count: Annotated[Optional[int], typer.Option(help="Number of frequencies from --from to --to.")] = None,
    workers: Annotated[int, typer.Option(min=1, help="Processes running frequencies side by side.")] = 2,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: the deck's output folder + '-transmissibility').")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write transmissibility.png.")] = True,
):
    """Stepped-sine transmissibility: steady peak |total acceleration| / amplitude at G and every point.

    Writes transmissibility.csv, transmissibility.json (how each frequency settled) and
    transmissibility.png.
    """
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from rbhyst.model.deck import ACCEL_UNITS, load_deck
    from rbhyst.files.outdir import staged_directory
    from rbhyst.analyses.transmissibility import stepped_sine, write_csv, write_json

    with user_errors():
        d = load_deck(deck)
        amplitudes, freqs = _sweep_request(d, direction, amplitude, units, frequencies, f_from, f_to, count)
        amplitudes = [a * ACCEL_UNITS[units] for a in amplitudes]
        console = Console(stderr=True)
        columns = (TextColumn("{task.description:<32}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                   TimeElapsedColumn())
        # refreshed by hand: no drawing thread in this process when the workers fork
        with Progress(*columns, console=console, transient=True, disable=not console.is_terminal,
                      auto_refresh=False) as bar:
            task = bar.add_task("transmissibility", total=None)

            def progress(label: str, done: int, total: int) -> None:
                bar.update(task, description=label, completed=done, total=total)
                bar.refresh()

            result = stepped_sine(d, direction, amplitudes, freqs, workers=workers, progress=progress)
        target = out if out is not None else _sibling_dir(d, deck, "-transmissibility")
        say_replaced(target, "transmissibility")
        with staged_directory(target) as tmp:
            write_csv(result, tmp / "transmissibility.csv")
            write_json(result, tmp / "transmissibility.json")
            if plots and d.output.plots:
                from rbhyst.report.transmissibility import plot_transmissibility

                plot_transmissibility(result, tmp / "transmissibility.png", title=d.title or "")
    for note in result.notes:
        say(f"note: {note}")
    table = result.table()
    i = result.columns.index(f"T_G_{direction}")
    for amp in dict.fromkeys(table[:, 1]):
        mine = table[table[:, 1] == amp]
        k = int(mine[:, 2 + i].argmax())
        say(f"{amp:g} m/s2: T_G_{direction} from {mine[:, 2 + i].min():.3g} to {mine[k, 2 + i]:.3g} "
            f"(at {mine[k, 0]:.4g} Hz) over {len(mine)} frequencies")
    say(f"wrote {target}")


def _sibling_dir(deck, deck_path: Path, suffix: str) -> Path:
    """Beside the run's folder (a folder holds the results of one command): <output folder><suffix>."""
    base = output_dir(deck, deck_path)
    if base.name in ("", ".."):
        base = base.resolve()
    return base.with_name(base.name + suffix)


@app.command("make-record", cls=Command)
def make_record(
    out: Annotated[Path, typer.Argument(help="CSV file to write: time_s,acceleration.")],
    duration: Annotated[float, typer.Option(min=0.1, help="Length [s].")] = 40.0,
    dt: Annotated[float, typer.Option(min=1e-5, help="Sampling step [s].")] = 0.01,
    pga: Annotated[float, typer.Option(min=0.0, help="Peak absolute acceleration, in --units.")] = 0.3,
    units: Annotated[str, typer.Option(help="Units written in the header (g, m/s2, cm/s2).")] = "g",
    seed: Annotated[int, typer.Option(help="Random seed: the same seed gives the same record.")] = 1940,
    f_g: Annotated[float, typer.Option(help="Kanai-Tajimi ground frequency [Hz].")] = 2.5,
):
    """A reproducible synthetic support acceleration (Clough-Penzien filtered white noise).

    The first line, a comment, is the command that made the file: rbhyst overwrites only
    files that begin with it.
    """
    import io
    import shlex

    import numpy as np

    from rbhyst.files.outdir import replace_own_file
    from rbhyst.model.synthetic import ground_motion

    with user_errors():
        t, acc = ground_motion(duration=duration, dt=dt, pga=pga, seed=seed, f_g=f_g)
        options = {"--duration": duration, "--dt": dt, "--pga": pga, "--units": units, "--seed": seed, "--f-g": f_g}
        mark = f"{RECORD_MARK} " + " ".join(f"{k} {shlex.quote(str(v))}" for k, v in options.items())
        buf = io.StringIO()
        np.savetxt(buf, np.column_stack([t, acc]), delimiter=",", comments="", fmt="%.6f,%.8e",
                   header=f"{mark}\ntime_s,acceleration_{units.replace('/', '_')}")
        replace_own_file(out, buf.getvalue(), RECORD_MARK)
    say(f"wrote {out}: {len(t)} samples at {dt:g} s, peak {pga:g} {units}, seed {seed}")


#: the first line of every record make-record writes (the readers skip '#' comments)
RECORD_MARK = "# rbhyst make-record"


@app.command("make-motion", cls=Command)
def make_motion(
    out: Annotated[Path, typer.Argument(help="Folder to write: m1_x1.csv, m1_x2.csv, ..., trs.csv, trs_fine.csv, "
                                             "records.csv, trs.png, motions.json.")],
    rrs: Annotated[Optional[str], typer.Option(help="ac156, ieee693, or a CSV RRS for x1 (frequency_hz and a value "
                                                    "column with its unit: sa_g, sa_m_s2).")] = None,
    rrs_x2: Annotated[Optional[str], typer.Option("--rrs-x2", help="A CSV RRS for x2 (vertical; with --axes 3 the "
                                                                   "second horizontal), with an RRS file for "
                                                                   "x1.")] = None,
    rrs_x3: Annotated[Optional[str], typer.Option("--rrs-x3", help="With --axes 3: a CSV RRS for x3, the "
                                                                   "vertical.")] = None,
    rrs_damping: Annotated[Optional[float], typer.Option(help="The damping ratio the RRS files are drawn for "
                                                              "(ieee693: 0.05 by default).")] = None,
    sds: Annotated[Optional[float], typer.Option(help="AC156: S_DS, in g.")] = None,
    z_over_h: Annotated[Optional[float], typer.Option(help="AC156: z/h, 0 at grade to 1 at the roof.")] = None,
    level: Annotated[Optional[str], typer.Option(help="IEEE 693: the performance level, high or moderate.")] = None,
    axes: Annotated[int, typer.Option(help="2: x1 horizontal and x2 vertical (a deck in the plane); 3: x1 and x2 "
                                           "horizontal, x3 vertical (a triaxial table, a deck in space).")] = 2,
    duration: Annotated[float, typer.Option(help="Length in s (AC156, IEEE 693: 30 s, 20 s of them strong "
                                                 "motion).")] = 30.0,
    dt: Annotated[float, typer.Option(help="Sampling step in s.")] = 0.005,
    seed: Annotated[int, typer.Option(help="Random seed: the same seed gives the same motions.")] = 1,
    motions: Annotated[int, typer.Option(min=1, help="Number of motions (each with its own noise).")] = 1,
    table: Annotated[Optional[str], typer.Option(help="The shake table's limits, any of displacement=D (m, peak "
                                                      "to peak), velocity=V (m/s), acceleration=A (g): every record "
                                                      "made within them.")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write trs.png.")] = True,
):
    """Spectrum-compatible support motions: one record per axis whose TRS lies within 0.9-1.3 of the RRS.

    The records are read by decks and by `rbhyst spectrum` (--units g); exit 3 when a motion
    cannot be matched, with what would work. Long: its signature is its many options.
    """
    import json
    import shlex

    from rbhyst.analyses.qualification import matching
    from rbhyst.analyses.qualification.rrs import requested_rrs
    from rbhyst.files.outdir import staged_directory

    keys = {"rrs": "--rrs", "rrs_x2": "--rrs-x2", "rrs_x3": "--rrs-x3", "damping": "--rrs-damping", "sds": "--sds",
            "z_over_h": "--z-over-h", "level": "--level", "duration": "--duration", "dt": "--dt"}
    with user_errors():
        if axes not in (2, 3):
            raise InputError(f"--axes: {axes}: 2 (x1 horizontal, x2 vertical) or 3 (x1, x2 horizontal, x3 vertical)")
        if rrs_x3 is not None and axes != 3:
            raise InputError("--rrs-x3: only with --axes 3 (with two axes the vertical is x2: --rrs-x2)")
        from rbhyst.analyses.qualification.table import read_table, table_problems

        limits, problems = read_table(table)
        spectra, standard = requested_rrs(rrs, rrs_x2, rrs_damping, sds, z_over_h, Path.cwd(), keys, level,
                                          rrs_x3, space=axes == 3)
        problems += matching.motion_problems(spectra, duration, dt, None, standard, keys)
        problems += table_problems(limits, {a: None if r.peak_min is None else r.peak_min / 9.80665
                                            for a, r in spectra.items()})
        if problems:
            raise InputError(problems)
        made = matching.make_motions(spectra, motions, duration, dt, seed, vertical="x3" if axes == 3 else "x2",
                                     table=limits)
        options = {"--rrs": rrs, "--rrs-x2": rrs_x2, "--rrs-x3": rrs_x3, "--rrs-damping": rrs_damping, "--sds": sds,
                   "--z-over-h": z_over_h, "--level": level, "--axes": axes if axes != 2 else None,
                   "--duration": duration, "--dt": dt, "--seed": seed, "--table": table}
        mark = f"{MOTION_MARK} " + " ".join(f"{k} {shlex.quote(str(v))}" for k, v in options.items() if v is not None)
        say_replaced(out, "make-motion")
        with staged_directory(out) as tmp:
            for m in made:
                for axis in m.records:
                    (tmp / matching.record_name(m, axis)).write_text(matching.record_text(m, axis, mark),
                                                                    encoding="utf-8")
            matching.write_tables(tmp, made)
            (tmp / "motions.json").write_text(json.dumps(matching.motions_summary(made, spectra, standard), indent=2)
                                              + "\n", encoding="utf-8")
            if plots:
                from rbhyst.report.qualification import plot_trs

                plot_trs(made, spectra, tmp / "trs.png")
    for line in _motion_lines(made):
        say(line)
    say(f"wrote {out}")


#: the first line of every record make-motion writes
MOTION_MARK = "# rbhyst make-motion"


@app.command("make-shock", cls=Command)
def make_shock(
    out: Annotated[Path, typer.Argument(help="Folder to write: shock_x1.csv (shock_x2.csv, shock_x3.csv), "
                                             "srs_check.csv, shocks.json, srs_check.png, records.png.")],
    srs: Annotated[Path, typer.Option(help="The SRS specification: a CSV of frequency_hz and the maximax SRS "
                                           "with its unit (srs_g, srs_m_s2), straight between breakpoints on "
                                           "log-log axes.")],
    q: Annotated[float, typer.Option("--q", help="The specification's quality factor Q = 1 / (2 damping).")] = 10.0,
    duration: Annotated[Optional[float], typer.Option(help="Length in s (default: 6 periods of the lowest "
                                                           "frequency).")] = None,
    method: Annotated[str, typer.Option(help="wavelets (each ends at rest by itself) or damped-sines "
                                             "(Smallwood's, compensated to end at rest).")] = "wavelets",
    table: Annotated[Optional[str], typer.Option(help="The shaker's limits, any of displacement=D (m, peak to "
                                                      "peak), velocity=V (m/s), acceleration=A (g).")] = None,
    seed: Annotated[int, typer.Option(help="Random seed: the same seed gives the same records.")] = 1,
    axes: Annotated[int, typer.Option(help="1: a record for x1; 3: for x1, x2 and x3 (each its own).")] = 1,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write srs_check.png and records.png.")] = True,
):
    """A shock a shaker can play whose maximax SRS lies within MIL-STD-810's -1.5/+3 dB of a
    specification at every 1/12-octave frequency of its range, starting and ending at rest.

    Exit 3 when no record can, with what would work.
    """
    import json
    import math
    import shlex

    from rbhyst.analyses.qualification.table import read_table
    from rbhyst.analyses.shock import synthesis
    from rbhyst.analyses.shock.specification import LOWER_DB, UPPER_DB, read_specification
    from rbhyst.files.outdir import staged_directory

    with user_errors():
        limits, problems = read_table(table)
        spec = read_specification(srs)
        if axes not in (1, 3):
            problems.append(f"--axes: {axes}: 1 (x1) or 3 (x1, x2, x3)")
        length = synthesis.default_duration(spec) if duration is None else duration
        problems += synthesis.shock_problems(q, method, {})
        if not (math.isfinite(length) and length > 0):
            problems.append(f"--duration: {length:g}: a length in s, above 0")
        if problems:
            raise InputError(problems)
        short = synthesis.duration_problem(spec, length)
        if short:
            raise AnalysisError(short)
        made = synthesis.make_shocks(spec, q, length, method, seed, ["x1", "x2", "x3"][:axes], limits)
        options = {"--srs": srs, "--q": q, "--duration": length, "--method": method, "--table": table,
                   "--seed": seed, "--axes": axes}
        mark = f"{SHOCK_MARK} " + " ".join(f"{k} {shlex.quote(str(v))}" for k, v in options.items() if v is not None)
        say_replaced(out, "make-shock")
        with staged_directory(out) as tmp:
            for s in made:
                (tmp / synthesis.record_name(s)).write_text(synthesis.record_text(s, mark), encoding="utf-8")
            (tmp / "srs_check.csv").write_text("\n".join(synthesis.check_rows(made)) + "\n", encoding="utf-8")
            data = synthesis.summary(made, spec, q, method, length, seed, limits)
            (tmp / "shocks.json").write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
            if plots:
                from rbhyst.report.shock_spectra import plot_shock_records, plot_srs_check

                what = f"{srs.name}, Q = {q:g}, {method}"
                plot_srs_check(made, tmp / "srs_check.png", (LOWER_DB, UPPER_DB), title=what)
                plot_shock_records(made, tmp / "records.png", title=what)
    for line in synthesis.shock_lines(made):
        say(line)
    say(f"wrote {out}")


#: the first line of every record make-shock writes
SHOCK_MARK = "# rbhyst make-shock"


def _motion_lines(made) -> list[str]:
    """make-motion's console lines: each record's TRS check, peak and strong motion, then each
    motion's correlation and coherence between its axes."""
    lines = []
    for m in made:
        for axis, r in m.records.items():
            least = "" if r.check.peak_min is None else f" (at least {r.check.peak_min / 9.80665:.3g} g)"
            strong = "" if r.strong_min is None else f" (at least {r.strong_min:g} s)"
            if r.table is not None:
                strong += (f"; asks the table {r.reached['displacement']:.3g} m peak to peak, "
                           f"{r.reached['velocity']:.3g} m/s, {r.reached['acceleration']:.3g} g (high-pass from "
                           f"{r.high_pass:.3g} Hz)")
            lines.append(f"motion {m.number} {axis}: TRS from {r.check.said()} at {len(r.check.fine_frequency)} "
                         f"frequencies ({r.iterations} iterations); peak {float(abs(r.acc_g).max()):.3g} g{least}; strong motion "
                         f"{r.strong:.3g} s{strong}")
        coherence = m.coherences()
        for pair, c in m.correlations.items():
            a, b = pair.split("_")
            lines.append(f"motion {m.number}: correlation of {a} and {b} {c:+.3f}; coherence "
                         f"{coherence[pair]['mean']:.3f} on average over {coherence[pair]['band_hz'][0]:.3g}-"
                         f"{coherence[pair]['band_hz'][1]:.3g} Hz (largest {coherence[pair]['max']:.3f})")
    return lines


@app.command(cls=Command)
def qualify(
    ctx: typer.Context,
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck (x1 horizontal, x2 vertical; in space x1 and x2 "
                                              "horizontal, x3 vertical), with a qualify section or the options "
                                              "below.")],
    standard: Annotated[Optional[str], typer.Option(help="The required response spectrum: ac156 or ieee693.")] = None,
    sds: Annotated[Optional[float], typer.Option(help="AC156: S_DS, in g.")] = None,
    z_over_h: Annotated[Optional[float], typer.Option(help="AC156: z/h, 0 at grade to 1 at the roof.")] = None,
    level: Annotated[Optional[str], typer.Option(help="IEEE 693: the performance level, high or moderate.")] = None,
    rrs: Annotated[Optional[str], typer.Option(help="A CSV RRS for x1 instead of a standard (in space: for x1 and "
                                                    "x2).")] = None,
    rrs_x2: Annotated[Optional[str], typer.Option("--rrs-x2", help="A CSV RRS for x2 (in space: for x2 alone, "
                                                                   "instead of --rrs's).")] = None,
    rrs_x3: Annotated[Optional[str], typer.Option("--rrs-x3", help="A CSV RRS for x3, the vertical of a deck in "
                                                                   "space.")] = None,
    rrs_damping: Annotated[Optional[float], typer.Option(help="The damping ratio the RRS files are drawn for "
                                                              "(ieee693: 0.05 by default).")] = None,
    motions: Annotated[Optional[str], typer.Option(help="How many motions to make, or 'deck' (its own "
                                                        "excitation.support).")] = None,
    seed: Annotated[Optional[int], typer.Option(help="Random seed of the motions (of the shocks, with --shock).")] = None,
    duration: Annotated[Optional[float], typer.Option(help="Length of each motion in s (AC156: 30; of each shock made, with --shock).")] = None,
    motion_dt: Annotated[Optional[float], typer.Option(help="Sample step of the motions in s.")] = None,
    table: Annotated[Optional[str], typer.Option(help="The shake table's limits, any of displacement=D (m, peak "
                                                      "to peak), velocity=V (m/s), acceleration=A (g): every motion "
                                                      "(every shock, with --shock) made within them.")] = None,
    statistic: Annotated[Optional[str], typer.Option(help="The demand over the motions: max (the largest, the "
                                                          "default) or mean (from 7 motions on, ASCE 7-10 "
                                                          "16.2.4).")] = None,
    integrator: Annotated[Optional[str], typer.Option(help="Override analysis.integrator.")] = None,
    dt: Annotated[Optional[float], typer.Option(help="Override analysis.dt, in s.")] = None,
    tolerance: Annotated[Optional[float], typer.Option(help="The accuracy asked for (see rbhyst run).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: the deck's output folder + '-qualify').")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write qualification.png.")] = True,
    report: Annotated[bool, typer.Option("--report", help="Also write report.html (see `rbhyst report`).")] = False,
    shock: Annotated[Optional[Path], typer.Option(help="A shock qualification to an SRS specification (a CSV, as "
                                                       "make-shock reads it): a shock matched per axis, each axis "
                                                       "in both directions.")] = None,
    pulse: Annotated[Optional[str], typer.Option(help="A shock qualification to a named pulse (see rbhyst "
                                                      "shock --pulse).")] = None,
):
    """The verdict of a deck against a required response spectrum: qualification.json and .png.

    With --shock, --pulse or the deck's qualify.shock: the verdict under shock, each axis in both
    directions (three shocks each, or qualify.shock.shocks), by the workflow of `rbhyst shock`:
    qualification.json and shock.json. Long: its signature is its many options.

    Exit 0: it qualifies; 1: it does not (each failed criterion said); 2: a mistake in the
    deck or options; 3: motions that cannot be matched, or a run that fails.
    """
    from rbhyst.analyses.qualification.verdict import output_files, qualify as judge, request, verdict_lines
    from rbhyst.files.outdir import check_free, staged_directory
    from rbhyst.model.deck import ANALYSIS_SECTIONS, load_deck

    with user_errors():
        d = load_deck(deck, need=ANALYSIS_SECTIONS)
        asked = {"standard": standard, "sds": sds, "z_over_h": z_over_h, "level": level, "rrs": rrs,
                 "rrs_x2": rrs_x2, "rrs_x3": rrs_x3, "rrs_damping": rrs_damping, "motions": motions, "seed": seed,
                 "duration": duration, "motion_dt": motion_dt, "statistic": statistic, "table": table}
        if _shock_qualification(d, deck, {**asked, "shock": shock, "pulse": pulse}, report, out, plots,
                                (integrator, dt, tolerance, command_line(ctx))):
            return
        req = request(d, asked)
        target = out if out is not None else _sibling_dir(d, deck, "-qualify")
        say_replaced(target, "qualify")
        check_free(target, output_files(req) + (["qualification.png"] if plots and d.output.plots else []))
        if report:
            from rbhyst.report.report_file import check_report_target

            check_report_target(target)
        with staged_directory(target) as tmp:
            v = judge(d, req, tmp, integrator=integrator, dt=dt, tolerance=tolerance, say=say,
                      command=command_line(ctx))
            if plots and d.output.plots:
                from rbhyst.report.qualification import plot_verdict

                plot_verdict(v.checks, req.rrs, v.criteria, v.passed, tmp / "qualification.png",
                             title=d.title or "", notes=v.heading, space="x3" in req.axes)
        _verdict_said(target, report, verdict_lines(v), v.passed)


#: ``rbhyst qualify``: the deck does not qualify
EXIT_VERDICT = 1


def _verdict_said(target: Path, report: bool, lines: list[str], passed: bool) -> None:
    """The end of a verdict's command (qualify, shock): the folder's report if asked, the verdict's
    lines, exit 1 on a fail."""
    if report:
        from rbhyst.report.report_file import write_report

        write_report(target)
    for line in lines:
        say(line)
    say(f"wrote {target}")
    if not passed:
        raise typer.Exit(EXIT_VERDICT)


def _shock_qualification(d, deck: Path, asked: dict, report: bool, out, plots: bool, run_options) -> bool:
    """``rbhyst qualify`` under shock, when the options or the deck ask for it (True: done)."""
    from rbhyst.analyses.shock import qualify as shock_qualify

    if not shock_qualify.wanted(d, asked):
        return False
    _qualify_shock(d, deck, shock_qualify.request(d, asked), out, plots, report, *run_options)
    return True


def _qualify_shock(d, deck: Path, req, out, plots: bool, report: bool, integrator, dt, tolerance, command) -> None:
    """``rbhyst qualify`` under shock: the shock workflow's files, and qualification.json."""
    import json

    from rbhyst.analyses.shock.qualify import qualification
    from rbhyst.analyses.shock.verdict import output_files, verdict_lines
    from rbhyst.analyses.shock.verdict import shock as judge
    from rbhyst.files.outdir import check_free, staged_directory

    target = out if out is not None else _sibling_dir(d, deck, "-qualify")
    say_replaced(target, "qualify")
    check_free(target, output_files(req) + ["qualification.json"])
    if report:
        from rbhyst.report.report_file import check_report_target

        check_report_target(target)
    with staged_directory(target) as tmp:
        v, drives, made = judge(d, req, tmp, integrator=integrator, dt=dt, tolerance=tolerance, say=say,
                                command=command)
        (tmp / "qualification.json").write_text(json.dumps(qualification(v.data), indent=2) + "\n",
                                                encoding="utf-8")
        if plots and d.output.plots:
            _shock_plots(drives, made, tmp)
    _verdict_said(target, report, verdict_lines(v), v.passed)


@app.command(cls=Command)
def schema(
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Write the schema to this file instead of standard output.")] = None,
):
    """The deck's JSON Schema (draft 2020-12), for editors that complete and check decks as they
    are typed: a TOML deck's first line `#:schema ./deck.schema.json` (taplo, Even Better TOML),
    a YAML deck's `# yaml-language-server: $schema=./deck.schema.json`.
    """
    import json

    from rbhyst.model.schema import deck_schema

    text = json.dumps(deck_schema(), indent=2, ensure_ascii=False) + "\n"
    if out is None:
        sys.stdout.write(text)
        return
    with user_errors():
        try:
            out.write_text(text, encoding="utf-8")
        except OSError as err:
            raise InputError(f"--out {out}: cannot write it ({err.strerror or err})") from None
    say(f"wrote {out}")


@app.command(cls=Command)
def shock(
    ctx: typer.Context,
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck, with a shock section or the options below.")],
    pulse: Annotated[Optional[str], typer.Option(help="A named pulse: 810h-functional-flight, 810h-functional-ground, "
                                                      "810h-crash-flight, 810h-crash-ground, 810c-basic-design, "
                                                      "202-condition-a (README, Shock).")] = None,
    record: Annotated[Optional[Path], typer.Option(help="A shock record instead of a pulse (time,value table, "
                                                         "starting at 0 s).")] = None,
    units: Annotated[Optional[str], typer.Option(help="Units of --record's values: g, m/s2 or cm/s2.")] = None,
    compensation: Annotated[Optional[str], typer.Option(help="A named pulse with pre- and post-pulses (pre-post) "
                                                             "or bare (none, the default).")] = None,
    shocks: Annotated[Optional[int], typer.Option(help="Shocks in each direction of each axis, one after the other "
                                                       "(default 3, MIL-STD-810H 516.8 Procedure I).")] = None,
    axes: Annotated[Optional[str], typer.Option(help="Comma-separated axes to shock (default: every axis of the "
                                                     "deck).")] = None,
    integrator: Annotated[Optional[str], typer.Option(help="Override analysis.integrator.")] = None,
    dt: Annotated[Optional[float], typer.Option(help="Override analysis.dt, in s.")] = None,
    tolerance: Annotated[Optional[float], typer.Option(help="The accuracy asked for (see rbhyst run).")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: the deck's output folder + '-shock').")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write pulse.png, srs.png and pvss.png.")] = True,
):
    """The verdict of a deck under shock along each direction of each axis: shock.json.

    Exit 0: it passes; 1: it does not (each failed criterion said); 2: a mistake in the deck or
    options; 3: a run that fails.
    """
    from rbhyst.analyses.shock.verdict import output_files, request, verdict_lines
    from rbhyst.analyses.shock.verdict import shock as judge
    from rbhyst.files.outdir import check_free, staged_directory
    from rbhyst.model.deck import ANALYSIS_SECTIONS, load_deck

    with user_errors():
        d = load_deck(deck, need=ANALYSIS_SECTIONS)
        req = request(d, {"pulse": pulse, "record": record, "units": units, "compensation": compensation,
                          "shocks": shocks, "axes": _split_list(axes, "--axes")})
        target = out if out is not None else _sibling_dir(d, deck, "-shock")
        check_free(target, output_files(req))
        with staged_directory(target) as tmp:
            v, drives, _ = judge(d, req, tmp, integrator=integrator, dt=dt, tolerance=tolerance, say=say,
                                 command=command_line(ctx))
            if plots and d.output.plots:
                _shock_plots(drives, [], tmp)
    _verdict_said(target, False, verdict_lines(v), v.passed)


def _shock_plots(drives: dict, made: list, folder: Path) -> None:
    """pulse.png, srs.png and pvss.png of a drive every axis shares; srs_check.png of SRS-matched ones."""
    from rbhyst.analyses.shock.verdict import drive_srs
    from rbhyst.report.shock_spectra import plot_pulse, plot_pvss, plot_srs, plot_srs_check

    if made:
        from rbhyst.analyses.shock.specification import LOWER_DB, UPPER_DB

        plot_srs_check(made, folder / "srs_check.png", (LOWER_DB, UPPER_DB), title="the drives")
        return
    drive = next(iter(drives.values()))
    if drive.pulse is not None:
        plot_pulse(drive.pulse, folder / "pulse.png", title=drive.source)
    srs = drive_srs(drive)
    plot_srs(srs, folder / "srs.png", title="the drive")
    plot_pvss(srs, folder / "pvss.png", title="the drive")


def output_dir(deck, deck_path: Path) -> Path:
    """output.directory relative to the deck's folder, default results/<deck stem>/."""
    if deck.output.directory is not None:
        p = Path(deck.output.directory)
        return p if p.is_absolute() else deck_path.parent / p
    return deck_path.parent / "results" / deck_path.stem


class Interrupted(BaseException):
    """SIGINT or SIGTERM. A BaseException, so that no ``except Exception`` swallows it, and not
    a KeyboardInterrupt, which typer turns into a silent exit 130."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _interrupt(signum, frame):
    outdir.received.append(signum)
    raise Interrupted(signum)


def main() -> None:
    """The entry point: Ctrl-C (exit 130) and SIGTERM (exit 143) end a command with one line, and
    the staging cleanup (rbhyst.files.outdir) sees them: nothing half-written stays behind."""
    outdir.received.clear()
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, _interrupt)
    try:
        app()
    except Interrupted as exc:
        done = outdir.written
        say("interrupted: nothing written" if not done else f"interrupted after writing {done[-1]}")
        outdir.received.clear()
        sys.exit(128 + exc.signum)


def entry() -> None:
    """The ``rbhyst`` command: ``main``, then out without the interpreter's teardown.

    Tearing down numba's and matplotlib's modules costs 0.15-0.25 s after every command and
    gives nothing back: the files are closed and flushed by then. A signal that arrives
    after the command has finished is ignored. The allocator keeps freed memory for the next
    array (rbhyst.allocator).
    """
    from rbhyst.allocator import keep_freed_memory

    keep_freed_memory()
    # A command makes some hundreds of thousands of objects that live to its end (modules,
    # classes, pydantic's validators, matplotlib's artists): the collector, run every 700 new
    # objects, went over them again and again (97 collections before a run of the seed deck,
    # 250 with its figures; 7-8 % of the command's time, measured). Every 50,000: cycles are
    # still collected in a long command (a sweep).
    gc.set_threshold(50_000, 10, 10)
    try:
        main()
        code = 0
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            code = exc.code or 0
        else:
            print(exc.code, file=sys.stderr)
            code = 1
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, signal.SIG_IGN)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()
