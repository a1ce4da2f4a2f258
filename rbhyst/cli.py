"""The command line: load -> assemble -> simulate -> write. Nothing below knows about the terminal."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Optional

import typer

from . import __version__
from .errors import AnalysisError, InputError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Nonlinear dynamics of 2D rigid bodies on Vaiana-Rosati hysteretic supports.",
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


@app.command()
def run(
    deck: Annotated[Path, typer.Argument(help="TOML or YAML deck.")],
    out: Annotated[Optional[Path], typer.Option("--out", help="Output folder (default: the deck's).")] = None,
    integrator: Annotated[Optional[str], typer.Option(help="Override analysis.integrator.")] = None,
    dt: Annotated[Optional[float], typer.Option(help="Override analysis.dt [s].")] = None,
    plots: Annotated[bool, typer.Option("--plots/--no-plots", help="Write PNG plots.")] = True,
):
    """Time-history analysis of the deck: time_history.csv, summary.json and PNG plots."""
    from .deck import load_deck
    from .model import assemble
    from .outdir import staged_directory
    from .results import ENERGY_WARN, write_csv, write_summary
    from .simulate import settings_from_deck, simulate

    with user_errors():
        d = load_deck(deck)
        settings = settings_from_deck(d, integrator=integrator, dt=dt)
        system = assemble(d, deck.parent)
        result = simulate(system, settings)
        for note in system.notes:  # after the run: a failing deck gets its error lines alone
            say(f"note: {note}")
        if result.record_substeps > 1:
            say(f"note: a record is sampled finer than dt = {settings.dt:g} s: "
                f"{result.record_substeps} substeps per step follow it (output stays on dt)")
        if result.substeps:
            say(f"note: {result.substeps} substeps (up to 2^{result.max_substep_level} per step) "
                "resolved stiff instants; see summary.json")
        if result.energy_balance > ENERGY_WARN:
            say(f"warning: energy balance error {result.energy_balance:.2%} exceeds {ENERGY_WARN:.0%}: "
                "reduce dt")
        target = out if out is not None else output_dir(d, deck)
        write_plots = plots and d.output.plots
        with staged_directory(target) as tmp:
            write_csv(result, tmp / "time_history.csv")
            write_summary(result, tmp / "summary.json")
            if write_plots:
                from .report.run import write_plots as _plots

                _plots(result, tmp)
    s = result.summary()
    pk = s["peaks"]
    say(f"{settings.integrator}, dt = {settings.dt:g} s, {result.steps} steps in {result.wall_s:.3g} s; "
        f"peaks |u1| = {pk['u1_m']:.4g} m, |u2| = {pk['u2_m']:.4g} m, |theta3| = {pk['theta3_rad']:.4g} rad")
    say(f"wrote {target}")

@app.command("calibrate-plot")
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
):
    """Force-displacement loops of VRM sets: loops.png, loops_<set>.csv, summary.json (fit.json with --data)."""
    from .calibration import header, loop_result, protocol, safe_names, write_json, write_loop_csv
    from .deck import load_deck
    from .outdir import staged_directory
    from .testdata import read_loop_data

    with user_errors():
        d = load_deck(deck)
        names = _chosen_sets(deck, d, sets)
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
        files = safe_names(names)
        with staged_directory(target) as tmp:
            for r in results:
                write_loop_csv(r, tmp / f"loops_{files[r.name]}.csv")
            write_json(summary, tmp / "summary.json")
            if measured is not None:
                write_json({**header("calibrate-plot"), "deck": deck.name, "data": measured.name,
                            "sets": {r.name: {"nrmse": r.nrmse, "r2": r.r2,
                                              "hysteretic_work_J": float(r.work[-1]),
                                              "dissipated_per_cycle_J": r.dissipated} for r in results}},
                           tmp / "fit.json")
            from .report.loops import plot_loops

            plot_loops(results, tmp / "loops.png", title=d.title)
    for r in results:
        fit = f"NRMSE {r.nrmse:.3%}, R^2 {r.r2:.5f}; " if r.f_data is not None else ""
        ed = r.dissipated
        cyc = f"{len(ed)} closed cycle{'s' if len(ed) != 1 else ''}, last dissipates {ed[-1]:.6g} J" if ed \
            else "no closed cycle"
        say(f"{r.name}: {fit}hysteretic work {r.work[-1]:.6g} J, {cyc}")
    say(f"wrote {target}")


@app.command()
def calibrate(
    data: Annotated[Path, typer.Argument(help="Measured loop: CSV with displacement and force columns, units in the header.")],
    set_name: Annotated[str, typer.Option("--set", help="The set to identify (its name in --init).")],
    init: Annotated[Path, typer.Option(help="Deck holding the starting values of the set.")],
    free: Annotated[Optional[list[str]], typer.Option(
        help="Parameters to fit (repeatable or comma-separated): loading.kb, kb+, kb- or kb for both "
             "branches. Default: all 16.")] = None,
    fix: Annotated[Optional[list[str]], typer.Option(help="Parameters to keep at their --init values.")] = None,
    starts: Annotated[int, typer.Option(min=1, help="Number of starts (the first is --init).")] = 6,
    seed: Annotated[int, typer.Option(help="Random seed for the extra starts.")] = 0,
    u_units: Annotated[Optional[str], typer.Option(help="Displacement units if the header has none.")] = None,
    f_units: Annotated[Optional[str], typer.Option(help="Force units if the header has none.")] = None,
    out: Annotated[Optional[Path], typer.Option(
        "--out", help="Output folder (default: results/<data stem>-calibrate/ beside the data).")] = None,
):
    """Identify a VRM set from measured loops: fitted.toml (deck fragment), fit.json, loops.png."""
    import tomllib

    from .calibration import (NAMES, check_orientation, deck_fragment, fit_set, header, loop_result,
                              parameters_dict, parse_names, round_set, safe_names, write_json, write_loop_csv)
    from .deck import load_deck, parse_deck
    from .outdir import staged_directory
    from .testdata import read_loop_data

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
        with staged_directory(target) as tmp:
            (tmp / "fitted.toml").write_text(fragment, encoding="utf-8")
            write_json(report, tmp / "fit.json")
            write_loop_csv(res, tmp / f"loops_{safe_names([set_name])[set_name]}.csv")
            from .report.loops import plot_loops

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


#: NRMSE above which ``calibrate`` warns that the fit does not follow the data
POOR_FIT_NRMSE = 0.05


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


@app.command()
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

    from .deck import load_deck
    from .model import assemble
    from .outdir import staged_directory
    from .simulate import grid, settings_from_deck
    from .study import check_dts, check_integrators, fixed_step_names, run_study, write_csv, write_json

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
        target = out if out is not None else _study_dir(d, deck)
        with staged_directory(target) as tmp:
            write_csv(result, tmp / "study.csv")
            write_json(result, tmp / "study.json")
            if plots and d.output.plots:
                from .report.study import write_plots

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


def _study_dir(deck, deck_path: Path) -> Path:
    """Beside the run's folder (a run replaces its folder whole): <output folder>-study."""
    base = output_dir(deck, deck_path)
    return base.with_name(base.name + "-study")


@app.command("make-record")
def make_record(
    out: Annotated[Path, typer.Argument(help="CSV file to write: time_s,acceleration.")],
    duration: Annotated[float, typer.Option(min=0.1, help="Length [s].")] = 40.0,
    dt: Annotated[float, typer.Option(min=1e-5, help="Sampling step [s].")] = 0.01,
    pga: Annotated[float, typer.Option(min=0.0, help="Peak absolute acceleration, in --units.")] = 0.3,
    units: Annotated[str, typer.Option(help="Units written in the header (g, m/s2, cm/s2).")] = "g",
    seed: Annotated[int, typer.Option(help="Random seed: the same seed gives the same record.")] = 1940,
    f_g: Annotated[float, typer.Option(help="Kanai-Tajimi ground frequency [Hz].")] = 2.5,
):
    """A reproducible synthetic support acceleration (Clough-Penzien filtered white noise)."""
    import numpy as np

    from .synthetic import ground_motion

    t, acc = ground_motion(duration=duration, dt=dt, pga=pga, seed=seed, f_g=f_g)
    out.parent.mkdir(parents=True, exist_ok=True)
    header = f"time_s,acceleration_{units.replace('/', '_')}"
    np.savetxt(out, np.column_stack([t, acc]), delimiter=",", header=header, comments="", fmt="%.6f,%.8e")
    say(f"wrote {out}: {len(t)} samples at {dt:g} s, peak {pga:g} {units}, seed {seed}")


def output_dir(deck, deck_path: Path) -> Path:
    """output.directory relative to the deck's folder, default results/<deck stem>/."""
    if deck.output.directory is not None:
        p = Path(deck.output.directory)
        return p if p.is_absolute() else deck_path.parent / p
    return deck_path.parent / "results" / deck_path.stem


def main() -> None:
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
