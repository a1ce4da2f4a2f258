"""How to integrate a scene: the deck's [analysis] and output.every after command-line overrides."""

from __future__ import annotations

from dataclasses import dataclass

from rbhyst.errors import InputError
from rbhyst.model.integrators import INTEGRATORS


#: the method a run steps with where the deck names none (and the first pass of the choice)
DEFAULT_INTEGRATOR = "chang"


@dataclass(frozen=True)
class Settings:
    integrator: str = DEFAULT_INTEGRATOR
    dt: float = 1e-3
    duration: float | None = None
    every: int = 1
    max_omega_dt: float = 0.5
    max_substep_level: int = 12
    #: newmark: Newton correction <= newton_tol x the step's increment, at most newton_max_iter iterations
    newton_tol: float = 1e-10
    newton_max_iter: int = 20
    #: the adaptive integrator's relative tolerance
    rtol: float = 1e-8
    #: the accuracy asked for (None: run as set, and estimate the error)
    tolerance: float | None = None
    #: above this estimated error a run warns
    warn_error: float = 0.01
    #: estimate the error of the run (an adaptive solution at two tolerances)
    estimate: bool = True
    #: output.points: (name, (x1, x2) in the deck's frame; (x1, x2, x3) in space), in deck order
    points: tuple[tuple[str, tuple[float, ...]], ...] = ()
    #: output.spectra: (dampings, periods in s) or None for no spectra
    spectra: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    #: output.spectra.kind: "sa" (response spectra) or "srs" (shock response spectra, the periods
    #: 1 / their frequencies)
    spectra_kind: str = "sa"
    #: every step of dt is split into this many times the compute steps the excitation needs:
    #: the refinement rbhyst.solve.choose makes to meet warn_error (rows stay on dt)
    refine: int = 1
    #: rbhyst chooses the compute step (and, past a budget, the method) that meets warn_error,
    #: dt being the output interval (rbhyst.solve.choose); False: exactly ``integrator`` at ``dt``
    choose: bool = False
    #: "small", "exact" (the system is assembled so) or "auto": small rotations where the terms
    #: they neglect stay below a tenth of warn_error, else the exact twin (rbhyst.solve.kinematic)
    kinematics: str = "small"


def settings_from_deck(deck, integrator: str | None = None, dt: float | None = None,
                       tolerance: float | None = None) -> Settings:
    """The deck's [analysis] and output.every, with command-line overrides validated like the deck."""
    from rbhyst.model.deck import check_runnable

    check_runnable(deck)
    a = deck.analysis
    if integrator is not None and integrator not in INTEGRATORS:
        raise InputError(f"--integrator: unknown {integrator!r}; choose one of {', '.join(INTEGRATORS)}")
    if dt is not None and not dt > 0:
        raise InputError(f"--dt: {dt} must be > 0")
    if tolerance is not None and not 0 < tolerance < 1:
        raise InputError(f"--tolerance: {tolerance} must be between 0 and 1 (a relative error)")
    named = integrator or a.integrator
    return Settings(
        integrator=named or DEFAULT_INTEGRATOR,
        choose=named is None,
        kinematics=a.kinematics,
        dt=dt or a.dt,
        duration=a.duration,
        every=deck.output.every,
        max_omega_dt=a.max_omega_dt,
        max_substep_level=a.max_substep_level,
        rtol=a.rtol,
        tolerance=tolerance if tolerance is not None else a.tolerance,
        warn_error=a.warn_error,
        estimate=a.estimate_error,
        points=tuple((p.name, tuple(p.point)) for p in deck.output.points or ()),
        spectra=_spectra(deck.output.spectra, dt or a.dt),
        spectra_kind="sa" if deck.output.spectra is None else deck.output.spectra.kind,
    )


def _spectra(spectra, dt: float):
    """(dampings, periods) of output.spectra; a shock spectrum's periods are 1 / its frequencies."""
    if spectra is None:
        return None
    if spectra.kind == "srs":
        return spectra.dampings, tuple(1.0 / f for f in reversed(spectra.frequencies(dt)))
    return spectra.dampings, spectra.periods
