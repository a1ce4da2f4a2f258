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
            say(f"error: {p}")
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
        for note in system.notes:
            say(f"note: {note}")
        result = simulate(system, settings)
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
