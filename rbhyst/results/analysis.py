"""The analysis of a scene from start to end, without files: plan, solve, estimate, checks.
What every run goes through (``rbhyst.run``, a sweep's case, a transmissibility block);
:mod:`rbhyst.api` adds the output folder and the plots."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from rbhyst.errors import accuracy_warnings
from rbhyst.model.deck import ANALYSIS_SECTIONS, Deck, load_deck
from rbhyst.model.settings import Settings, settings_from_deck
from rbhyst.model.system import System, assemble
from rbhyst.solve.result import Result


def deck_of(deck: Deck | str | Path) -> Deck:
    """A Deck, or the deck at a path, validated for a run."""
    return deck if isinstance(deck, Deck) else load_deck(deck, need=ANALYSIS_SECTIONS)


def scene(d: Deck, integrator: str | None = None, dt: float | None = None, tolerance: float | None = None,
          estimate: bool | None = None) -> tuple[System, Settings]:
    """A deck as the System it describes and the settings to run it with."""
    settings = settings_from_deck(d, integrator=integrator, dt=dt, tolerance=tolerance)
    if estimate is not None:
        settings = dataclasses.replace(settings, estimate=estimate)
    return assemble(d, d.base), settings


def plan(system: System, settings: Settings):
    """The stepping plan (rbhyst.solve.plan): what can fail before anything runs fails here."""
    from rbhyst.solve.plan import prepare

    if settings.tolerance is not None:
        settings = dataclasses.replace(settings, integrator="adaptive")
    return prepare(system, settings)


def analyse(system: System, settings: Settings, keep: bool = True, csv=None, planned=None,
            progress=None, spare_core: bool | None = None) -> Result:
    """One run and its estimate, or (with a tolerance) the run that meets it, or (a deck that
    names no integrator) the run rbhyst chose to meet warn_error (rbhyst.solve.choose); with
    analysis.kinematics = "auto", in the kinematics that scene needs; then its notes and
    warnings. ``csv``: where the rows are streamed (rbhyst.solve.plan.Rows; a
    rbhyst.results.writers.CsvWriter). ``spare_core``: whether the estimate may take a second
    core (rbhyst.solve.estimate; None: where this process may run on more than one; a sweep's
    worker says False)."""
    from rbhyst.results.checks import diagnose
    from rbhyst.solve.choose import answer_at, chosen_run, estimated_run
    from rbhyst.solve.estimate import meet_tolerance, warnings_for
    from rbhyst.solve.kinematic import chosen_exact, kinematics_summary, kinematics_warning, needs_exact

    if spare_core is None:
        from rbhyst.cores import usable_cores

        spare_core = usable_cores() > 1
    auto = settings.kinematics == "auto" and any(c.rotation for c in system.coordinates)
    if settings.tolerance is not None:
        if progress is not None:
            progress(0, 0, f"meeting the tolerance {settings.tolerance:g}")
        result = meet_tolerance(system, settings, keep=keep, csv=csv)
        if auto and needs_exact(result, settings)[0]:
            from rbhyst.model.kinematics import exact_twin

            twin = exact_twin(result.system)
            if twin is not None:
                small = result
                result = meet_tolerance(twin, settings, keep=keep, csv=csv)
                result.kinematics = chosen_exact(small, settings, result)
    elif settings.choose and settings.estimate:
        result = chosen_run(system, settings, keep=keep, csv=csv, progress=progress, spare_core=spare_core)
    else:
        # with kinematics to choose, the small-rotation run is a trial: its rows are written once
        # the choice is made (run again: the same numbers; or the exact twin's)
        result = estimated_run(system, settings, keep=keep, csv=None if auto else csv, planned=planned,
                               progress=progress, spare_core=spare_core)
        if auto:
            result = answer_at(result, result.settings, needs_exact(result, settings)[0], keep, csv, rerun=True,
                               progress=progress)
    result.notes, result.warnings = diagnose(result)
    if result.spectra is not None:
        from rbhyst.solve.located import unfinished_note
        from rbhyst.solve.located_shock import excitation_end, residual_note

        dampings, periods = settings.spectra
        t_end = result.steps * result.settings.dt
        if settings.spectra_kind == "srs":
            note = residual_note(result.spectra, t_end)
        else:
            end = excitation_end(system.excitation) if system.excitation.signals else None
            note = unfinished_note(end, t_end, periods, dampings)
        result.notes += [note] if note else []
    result.warnings += accuracy_warnings(warnings_for(result.accuracy, result.settings, result.stats, result))
    if result.kinematics is None:
        result.kinematics = kinematics_summary(result, result.settings)
    result.warnings += accuracy_warnings(kinematics_warning(result.kinematics, result.settings.warn_error, result))
    return result


def run_deck(deck, keep: bool = True, spare_core: bool | None = None, **options) -> Result:
    """A deck's analysis in memory (``options``: integrator, dt, tolerance, estimate)."""
    system, settings = scene(deck_of(deck), **options)
    return analyse(system, settings, keep=keep, spare_core=spare_core)
