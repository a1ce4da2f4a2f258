"""The analysis of a scene from start to end, without files: plan, solve, estimate, checks.
What every run goes through (``rbhyst.run``, a sweep's case, a transmissibility block);
:mod:`rbhyst.api` adds the output folder and the plots."""

from __future__ import annotations

import dataclasses
from pathlib import Path

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
    """One run and its estimate, or (with a tolerance) the run that meets it; then its notes
    and warnings. ``csv``: where the rows are streamed (rbhyst.solve.plan.Rows; a
    rbhyst.results.writers.CsvWriter). ``spare_core``: whether the estimate may take a second
    core (rbhyst.solve.estimate; None: where this process may run on more than one; a sweep's
    worker says False)."""
    from rbhyst.results.checks import diagnose
    from rbhyst.solve.estimate import estimate, meet_tolerance, warnings_for

    if settings.tolerance is not None:
        if progress is not None:
            progress(0, 0, f"meeting the tolerance {settings.tolerance:g}")
        result = meet_tolerance(system, settings, keep=keep, csv=csv)
    else:
        planned = planned or plan(system, settings)
        if keep:
            planned.check_size(keep=True)
        companion = _companion(planned) if settings.estimate else None
        result = planned.run(keep=keep, csv=csv, progress=progress, tap=companion and companion[1])
        if settings.estimate:
            if csv is not None:
                # the rows written first (their threads format them while the loop steps): an
                # estimate beside them took 30-60 % longer, and the two together no less time
                csv.wait()
            if progress is not None:
                progress(0, 0, "estimating the error")
            if spare_core is None:
                from rbhyst.cores import usable_cores

                spare_core = usable_cores() > 1
            result.accuracy = estimate(result, settings, companion=companion, spare_core=spare_core)
    result.notes, result.warnings = diagnose(result)
    if result.spectra is not None:
        from rbhyst.solve.located import unfinished_note

        dampings, periods = settings.spectra
        ends = [signal.end for signal in system.excitation.signals.values()]
        end = max(ends) if ends and None not in ends else None  # (a sine without end never ends)
        note = unfinished_note(end, result.steps * result.settings.dt, periods, dampings)
        result.notes += [note] if note else []
    result.warnings += warnings_for(result.accuracy, result.settings, result.stats)
    from rbhyst.solve.kinematic import kinematics_summary, kinematics_warning

    result.kinematics = kinematics_summary(result, result.settings)
    result.warnings += kinematics_warning(result.kinematics, result.settings.warn_error)
    return result


def run_deck(deck, keep: bool = True, spare_core: bool | None = None, **options) -> Result:
    """A deck's analysis in memory (``options``: integrator, dt, tolerance, estimate)."""
    system, settings = scene(deck_of(deck), **options)
    return analyse(system, settings, keep=keep, spare_core=spare_core)



def _companion(planned):
    """(plan, tap) where the run's error can come from its companion (rbhyst.solve.companion)."""
    from rbhyst.solve import companion
    from rbhyst.solve.plan import FixedStepPlan

    if not isinstance(planned, FixedStepPlan) or companion.unfit(planned) is not None:
        return None
    return planned, companion.RunTap(planned)
