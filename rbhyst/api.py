"""The Python API: what the command line does, for scripts and notebooks.

    import rbhyst
    deck = rbhyst.load_deck("decks/seed_wri.toml")        # validated (errors as InputError)
    res = rbhyst.run(deck)                                # or rbhyst.run("path.toml"); -> Result
    res.to_pandas(); res.summary(); res.write("results/x", plots=False)
    deck2 = deck.with_values({"hysteresis.wri_shear.loading.kb": 2.2e5, "body.mass": 700.0})

Top layer: the one pipeline of a run, deck -> model -> plan -> solve -> estimate -> result ->
files, in :func:`run`.
"""

from __future__ import annotations

from pathlib import Path

from rbhyst.errors import InputError, issue
from rbhyst.model.deck import Deck, load_deck
from rbhyst.solve.result import Result

__all__ = ["load_deck", "run", "write", "modes"]

#: the sections the body's modes need
MODES_SECTIONS = ("body", "elements")


def run(deck: Deck | str | Path, integrator: str | None = None, dt: float | None = None,
        out: str | Path | None = None, plots: bool | None = None, tolerance: float | None = None,
        estimate: bool | None = None, keep: bool = True, monitor=None, command: str | None = None) -> Result:
    """Run a deck (a Deck or a path) and return its Result, with its error estimated; each of
    its warnings (``Result.warnings``) is also issued through Python's ``warnings``, as an
    ``rbhyst.AccuracyWarning`` or an ``rbhyst.ModelWarning``.

    Without ``out`` the rows stay in memory (``Result.table``, ``to_pandas``). With ``out``
    they are streamed into ``out/time_history.csv`` beside summary.json and, if ``plots``
    (default: the deck's output.plots), the PNGs, and only the reductions stay in memory:
    the way to run what does not fit. ``tolerance``: the accuracy asked for (rbhyst chooses
    how, see docs/explanation/accuracy.md); ``estimate``: whether to estimate the error (default: the
    deck's analysis.estimate_error, true); ``keep=False`` without ``out``: keep only the
    reductions (peaks, extremes, accuracy), as a sweep does. ``monitor``: an object with
    ``note(text)`` (what to say before the run starts, such as the size of a large CSV) and
    ``update(done, total, label)`` (how far it is), for a caller that shows them as it goes.
    ``command``: the command line to record in summary.json's ``provenance`` (beside the time,
    the version and the sha256 of the deck and of every file it names); None: the Python API.
    """
    from rbhyst.files.provenance import provenance
    from rbhyst.model.inputs import deck_inputs
    from rbhyst.results.analysis import analyse, deck_of, plan, scene
    from rbhyst.results.writers import deck_as_run

    d = deck_of(deck)
    system, settings = scene(d, integrator=integrator, dt=dt, tolerance=tolerance, estimate=estimate)
    facts = provenance(command, deck_inputs(d))  # (after the scene, which says a missing record as its own)
    as_run = deck_as_run(d, integrator=integrator, dt=dt, tolerance=tolerance, estimate_error=estimate)
    progress = None if monitor is None else monitor.update
    if out is None:
        result = analyse(system, settings, keep=keep, progress=progress)
        result.writer = write
        result.deck = as_run
        result.provenance = facts
        issue(result.warnings)
        return result
    from rbhyst.files.outdir import staged_directory
    from rbhyst.results.writers import CsvWriter

    planned = plan(system, settings)  # what can fail before a file is touched
    early = planned.check_size(keep=False, folder=Path(out)) + replaced_results(Path(out), "run", as_run)
    for note in early if monitor is not None else ():
        monitor.note(note)
    draw = d.output.plots if plots is None else plots
    with staged_directory(Path(out)) as tmp:
        csv = CsvWriter(tmp / "time_history.csv")
        try:
            result = analyse(system, settings, keep=False, csv=csv, planned=planned, progress=progress)
            result.notes = early + result.notes
            result.deck = as_run
            result.provenance = facts
            if progress is not None and draw:
                progress(0, 0, "drawing the figures")
            # (while the last rows are written; the figures wait for them: a process with a thread
            # does not fork, and they are drawn on two cores by forking, rbhyst.report.parallel)
            _write_rest(result, tmp, draw, before_drawing=csv.wait)
        finally:
            csv.wait()
    result.csv_path = Path(out) / "time_history.csv"
    result.writer = write
    issue(result.warnings)
    return result


def replaced_results(folder: Path, command: str = "run", as_run: dict | None = None) -> list[str]:
    """A note where ``folder`` holds results that ``rbhyst command`` will replace: another
    command's (by the files its manifest lists), or, for ``run``, another deck's (the
    summary.json rbhyst wrote there, its deck's title other than this one's: a deck edited and
    run again replaces its own results, as it is meant to)."""
    import json

    from rbhyst.files.outdir import results_of

    folder = Path(folder)
    before = results_of(folder)
    if before is None:
        return []
    if before != command:
        return [f"{folder}: replaces the results of rbhyst {before} that were there"]
    if command != "run" or as_run is None:
        return []
    try:
        summary = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return []
    deck = summary.get("deck") if isinstance(summary, dict) else None
    if not isinstance(deck, dict) or deck.get("title") == as_run.get("title"):
        return []
    old = deck.get("title") or "(untitled)"
    return [f"{folder}: replaces the results of another deck, {old!r}, that were there"]


def modes(deck: Deck | str | Path, amplitude: float | None = None, stiffness: str | None = None) -> dict:
    """The undamped natural frequencies and mode shapes of a deck's body on its elements, without
    running anything: exactly summary.json's ``modes`` (coordinates, frequencies_hz ascending,
    shapes, stiffness; ``at_rest`` with the tangents at the static equilibrium under gravity).
    Only [body], [hysteresis] and [[elements]] are needed; a mistake is an InputError, elements
    that cannot carry the weight an AnalysisError.

    With ``amplitude`` (m): the modes with every element at its effective (secant) stiffness on
    the steady cycle of that amplitude (``stiffness="secant"``, the default) or at its tangent
    just after a reversal of it (``"reversal"``), rbhyst.model.effective; the same form, with
    ``amplitude_m``."""
    from rbhyst.model.system import assemble
    from rbhyst.solve.modes import REVERSAL, SECANT, amplitude_modes, modes_summary

    problems = []
    if stiffness is not None and amplitude is None:
        problems.append(f"stiffness: {stiffness!r} needs an amplitude (the cycle it is taken on)")
    if stiffness is not None and stiffness not in (SECANT, REVERSAL):
        problems.append(f"stiffness: {stiffness!r}: {SECANT} or {REVERSAL}")
    if amplitude is not None and not (isinstance(amplitude, (int, float)) and amplitude > 0):
        problems.append(f"amplitude: {amplitude!r}: a displacement amplitude > 0 in m")
    if problems:
        raise InputError(problems)
    d = deck if isinstance(deck, Deck) else load_deck(deck, need=MODES_SECTIONS)
    system = assemble(d, d.base, run=False)
    if amplitude is None:
        return modes_summary(system)
    try:
        found = amplitude_modes(system, float(amplitude), stiffness or SECANT)
    except OverflowError as exc:
        raise InputError(f"amplitude: {amplitude:g} m: a set's exponential overflows on that cycle ({exc})") from None
    return {**found.summary(), "amplitude_m": float(amplitude)}


def write(result: Result, out: str | Path, plots: bool = True) -> Path:
    """The files ``rbhyst run`` writes, from a result kept in memory."""
    from rbhyst.files.outdir import staged_directory
    from rbhyst.results.writers import write_csv

    if result.table is None:
        raise InputError(f"this result was streamed to {result.csv_path}; its rows are not in memory to write again")
    with staged_directory(Path(out)) as tmp:
        write_csv(result, tmp / "time_history.csv")
        _write_rest(result, tmp, plots)
    return Path(out)


def _write_rest(result: Result, folder: Path, plots: bool, before_drawing=None) -> None:
    from rbhyst.results.writers import spectra_file, write_spectra_csv, write_summary

    write_summary(result, folder / "summary.json")
    if result.spectra is not None:
        write_spectra_csv(result.spectra, folder / spectra_file(result.spectra))
    if plots:
        from rbhyst.report.run import write_plots  # (matplotlib's import)

        if before_drawing is not None:
            before_drawing()
        write_plots(result, folder)
