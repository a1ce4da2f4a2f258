"""The Python API: what the command line does, for scripts and notebooks.

    import rbhyst
    deck = rbhyst.load_deck("decks/seed_wri.toml")        # validated (errors as InputError)
    res = rbhyst.run(deck)                                # or rbhyst.run("path.toml"); -> Result
    res.to_pandas(); res.summary(); res.write("results/x", plots=False)
    deck2 = deck.with_values({"hysteresis.wri_shear.loading.kb": 2.2e5, "body.mass": 700.0})
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from .deck import ANALYSIS_SECTIONS, Deck, load_deck
from .errors import InputError
from .results import Result, write_summary

__all__ = ["load_deck", "run", "write"]


def _deck(deck: Deck | str | Path) -> Deck:
    return deck if isinstance(deck, Deck) else load_deck(deck, need=ANALYSIS_SECTIONS)


def run(deck: Deck | str | Path, integrator: str | None = None, dt: float | None = None,
        out: str | Path | None = None, plots: bool | None = None, tolerance: float | None = None,
        estimate: bool | None = None, keep: bool = True, monitor=None) -> Result:
    """Run a deck (a Deck or a path) and return its Result, with its error estimated.

    Without ``out`` the rows stay in memory (``Result.table``, ``to_pandas``). With ``out``
    they are streamed into ``out/time_history.csv`` beside summary.json and, if ``plots``
    (default: the deck's output.plots), the PNGs, and only the reductions stay in memory:
    the way to run what does not fit. ``tolerance``: the accuracy asked for (rbhyst chooses
    how, see README "Accuracy"); ``estimate``: whether to estimate the error (default: the
    deck's analysis.estimate_error, true); ``keep=False`` without ``out``: keep only the
    reductions (peaks, extremes, accuracy), as a sweep does. ``monitor``: an object with
    ``note(text)`` (what to say before the run starts, such as the size of a large CSV) and
    ``update(done, total, label)`` (how far it is), for a caller that shows them as it goes.
    """
    from .model import assemble
    from .settings import settings_from_deck

    d = _deck(deck)
    settings = settings_from_deck(d, integrator=integrator, dt=dt, tolerance=tolerance)
    if estimate is not None:
        settings = dataclasses.replace(settings, estimate=estimate)
    system = assemble(d, d.base)
    as_run = deck_as_run(d, integrator=integrator, dt=dt, tolerance=tolerance, estimate_error=estimate)
    progress = None if monitor is None else monitor.update
    if out is None:
        result = _solve(system, settings, keep=keep, progress=progress)
        result.deck = as_run
        return result
    from .outdir import staged_directory

    plan = _plan(system, settings)  # what can fail before a file is touched
    early = plan.check_size(keep=False, folder=Path(out))
    for note in early if monitor is not None else ():
        monitor.note(note)
    with staged_directory(Path(out)) as tmp:
        result = _solve(system, settings, keep=False, csv_path=tmp / "time_history.csv", plan=plan,
                        progress=progress)
        result.notes = early + result.notes
        result.deck = as_run
        if progress is not None and (d.output.plots if plots is None else plots):
            progress(0, 0, "drawing the figures")
        _write_rest(result, tmp, d.output.plots if plots is None else plots)
    result.csv_path = Path(out) / "time_history.csv"
    return result


def deck_as_run(deck: Deck, **overrides) -> dict:
    """The deck's keys as given, with the run's overrides (integrator, dt, tolerance,
    estimate_error) in [analysis]: what summary.json keeps of the deck, so that a report can show what ran."""
    data = deck.model_dump(mode="json", exclude_unset=True)
    given = {k: v for k, v in overrides.items() if v is not None}
    if given:
        data.setdefault("analysis", {}).update(given)
    return data


def _plan(system, settings):
    from .simulate import prepare

    if settings.tolerance is not None:
        settings = dataclasses.replace(settings, integrator="adaptive")
    return prepare(system, settings)


def _solve(system, settings, keep: bool, csv_path=None, plan=None, progress=None) -> Result:
    """One run and its estimate, or (with a tolerance) the run that meets it."""
    from .accuracy import estimate, meet_tolerance, warnings_for
    from .checks import diagnose

    if settings.tolerance is not None:
        if progress is not None:
            progress(0, 0, f"meeting the tolerance {settings.tolerance:g}")
        result = meet_tolerance(system, settings, keep=keep, csv_path=csv_path)
    else:
        plan = plan or _plan(system, settings)
        if keep:
            plan.check_size(keep=True)
        result = plan.run(keep=keep, csv_path=csv_path, progress=progress)
        if settings.estimate:
            if progress is not None:
                progress(0, 0, "estimating the error")
            result.accuracy = estimate(result, settings)
    result.notes, result.warnings = diagnose(result)
    if result.spectra is not None:
        from .response.located import unfinished_note

        dampings, periods = settings.spectra
        ends = [signal.end for signal in system.excitation.signals.values()]
        end = max(ends) if ends and None not in ends else None  # (a sine without end never ends)
        note = unfinished_note(end, result.steps * result.settings.dt, periods, dampings)
        result.notes += [note] if note else []
    result.warnings += warnings_for(result.accuracy, result.settings, result.stats)
    return result


def write(result: Result, out: str | Path, plots: bool = True) -> Path:
    """The files ``rbhyst run`` writes, from a result kept in memory."""
    from .outdir import staged_directory
    from .results import write_csv

    if result.table is None:
        raise InputError(f"this result was streamed to {result.csv_path}; its rows are not in memory to write again")
    with staged_directory(Path(out)) as tmp:
        write_csv(result, tmp / "time_history.csv")
        _write_rest(result, tmp, plots)
    return Path(out)


def _write_rest(result: Result, folder: Path, plots: bool) -> None:
    write_summary(result, folder / "summary.json")
    if result.spectra is not None:
        from .response.located import write_spectra_csv

        write_spectra_csv(result.spectra, folder / "spectra.csv")
    if plots:
        from .report.run import write_plots

        write_plots(result, folder)
