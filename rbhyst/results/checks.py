"""What a finished run says about itself: notes (information) and warnings (a result to doubt)."""

from __future__ import annotations

import math

import numpy as np

from rbhyst.errors import ModelWarning, Warned, accuracy_warnings
from rbhyst.solve.result import ENERGY_WARN, Result

def diagnose(result: Result) -> tuple[list[str], list[str]]:
    """Notes and warnings of a run, in the words the command line prints."""
    notes = list(result.system.notes)
    warnings: list[str] = list(result.system.warnings)  # (the deck's magnitudes: rbhyst.model.plausible)
    s, st = result.settings, result.stats
    ex = result.system.excitation
    t_end = st.steps * s.dt
    if not ex.signals:
        warnings.append("the deck has no excitation: the body stays at rest and every response is zero")
    elif not ex.acts_before(t_end):
        warnings.append(f"no excitation acts within the analysis (0 to {t_end:g} s): every response is zero")
    if st.record_substeps > 1:
        notes.append(f"the excitation is sampled finer than dt = {s.dt:g} s, or off its steps: "
                     f"{st.record_substeps} substeps per step follow it (output stays on dt)")
    notes += unresolved_signals(result)
    if st.substeps:
        notes.append(f"{st.substeps} substeps (up to 2^{st.max_substep_level} per step) resolved stiff instants; "
                     "see summary.json")
    if result.energy_balance > ENERGY_WARN:
        warnings += accuracy_warnings([f"energy balance error {result.energy_balance:.2%} exceeds "
                                       f"{ENERGY_WARN:.0%}: reduce dt"])
    # rotations beyond the seed's small ones: rbhyst.solve.kinematic says by how much, in numbers
    warnings += stroke_warnings(result)
    warnings += response_warnings(result)
    if result.system.static is not None:
        more_notes, more_warnings = gravity_checks(result)
        notes += more_notes
        warnings += more_warnings
    return notes, [w if isinstance(w, Warned) else Warned(w, ModelWarning) for w in warnings]


#: a static rotation under the weight alone beyond this (rad) says the deck is likely wrong
STATIC_ROTATION_WARN = 0.05


def gravity_checks(result: Result) -> tuple[list[str], list[str]]:
    """The static preload (a note), and warnings where its deflection is implausible: beyond the
    body's size or the seed's small rotations, an element beyond its stroke before anything moves
    (a g far from the standard one is the deck's mistake: rbhyst.model.deck.Body, gravity_check)."""
    system = result.system
    st = system.static
    w = system.weight
    coords = system.coordinates
    moving = [j for j, c in enumerate(coords) if not c.rotation]
    spin = [j for j, c in enumerate(coords) if c.rotation]
    q = system.to_deck(st.q) if hasattr(system, "to_deck") else st.q
    size = system.body.extent
    at = ", ".join(f"{c.key('d')} = {x:.4g} {c.d[1]}" for c, x in zip(coords, q))
    notes = [f"body.gravity: the weight {float(np.linalg.norm(w[moving])):.6g} N rests on the elements at {at} "
             "(the static preload; time_history.csv is measured from there)"]
    warnings = []
    shift = float(np.linalg.norm(q[moving]))
    turn = float(np.linalg.norm(q[spin])) if spin else 0.0
    if shift > size or turn > STATIC_ROTATION_WARN:
        warnings.append(f"body.gravity: the static deflection under the weight is {shift:.4g} m and {turn:.4g} rad, "
                        f"against a body of {size:.4g} m: beyond what the elements' sets and the seed's small "
                        "rotations describe; check body.gravity, body.mass and the sets' stiffness")
    u = system.expand(st.st[None, :, 0])[0]
    k = 0
    for el in system.elements:
        if el.stroke is not None:
            lo, hi = el.stroke
            for j in range(el.count):
                if not lo <= u[k + j] <= hi:
                    warnings.append(f"element e{k + j + 1} ({_which(el)}) is beyond its stroke under the weight "
                                    f"alone: {u[k + j]:.4g} m against [{lo:g}, {hi:g}] m")
        k += el.count
    return notes, warnings


#: rows of dt per sine period or pulse duration below which the rows cannot show the response
ROWS_PER_FEATURE = 10


def unresolved_signals(result: Result) -> list[str]:
    """Analytic signals too fast for the output's dt: the integration follows them (substeps), the
    peaks and spectra see every compute step, but the rows sample at dt."""
    from rbhyst.model.signals import Pulse

    s = result.settings
    t_end = result.stats.steps * s.dt
    fast: dict[tuple[str, float], list[str]] = {}
    for key, signal in result.system.excitation.signals.items():
        if not hasattr(signal, "breakpoints") or not signal.acts_before(t_end):
            continue  # (records: their own note)
        feature, what = ((signal.duration, f"a {signal.duration:.4g} s {signal.kind} pulse") if isinstance(signal, Pulse)
                         else (2 * math.pi / signal.omega, f"a {signal.omega / (2 * math.pi):.4g} Hz sine"))
        if feature / s.dt < ROWS_PER_FEATURE:
            fast.setdefault((what, feature), []).append(SIGNAL_KEYS[key])
    return [f"{', '.join(keys)}: {what} spans {feature / s.dt:.2g} rows of dt = {s.dt:g} s: the integration "
            f"follows it and the peaks, extremes and spectra see every compute step, but the rows of "
            f"time_history.csv and the plots show the response at dt only; dt = {feature / ROWS_PER_FEATURE:.3g} s "
            f"({ROWS_PER_FEATURE} rows) would show it" for (what, feature), keys in fast.items()]


#: a signal's place in the deck
SIGNAL_KEYS = {"ag1": "excitation.support.x1", "ag2": "excitation.support.x2", "p1": "excitation.force.p1",
               "p2": "excitation.force.p2", "m3": "excitation.force.m3", "ag3": "excitation.support.x3",
               "p3": "excitation.force.p3", "m1": "excitation.force.m1", "m2": "excitation.force.m2"}


def _which(el) -> str:
    """An element as a warning names it: its set, and the isolator direction it is, if one."""
    if getattr(el, "isolator", None) is None:
        return repr(el.hysteresis)
    return f"{el.label}, {el.hysteresis!r}"


def stroke_warnings(result: Result) -> list[str]:
    """An element beyond its stroke: which, how far, when."""
    from rbhyst.solve.result import stroke_use

    out, k = [], 1
    for el in result.system.elements:
        if el.stroke is not None:
            use = stroke_use(result.extremes, f"e{k}_u_m", el.stroke)
            if use["utilization"] > 1.0:
                span = f"e{k}" if el.count == 1 else f"e{k}-e{k + el.count - 1}"
                out.append(f"element {span} ({_which(el)}) goes beyond its stroke: {use['peak_deformation_m']:.4g} m "
                           f"at t = {use['time_of_peak_s']:.4g} s against a limit of "
                           f"{el.stroke[1] if use['peak_deformation_m'] > 0 else el.stroke[0]:g} m "
                           f"({use['utilization']:.0%} of it)" + _beside(el))
        k += el.count
    return out


def _beside(el) -> str:
    """What a stroke warning says of the element's stop, where it has one."""
    if el.stop is None:
        return ""
    lo, hi = el.stop[:2]
    where = "within" if el.stroke[0] <= lo and hi <= el.stroke[1] else "beyond"
    return (f"; it has a stop at [{lo:g}, {hi:g}] m ({where} the stroke), which bears it from there: the "
            "stroke is only compared, the stop is what the mount meets")


def response_warnings(result: Result) -> list[str]:
    """A response no mounted body survives (rbhyst.model.plausible.response_warnings): G's
    displacement against the body's size and the elements' strokes, its largest rotation."""
    from rbhyst.model.plausible import response_warnings as judged

    system, e = result.system, result.extremes
    moving = {c.key("d"): e.peak(c.column("d")) for c in system.coordinates if not c.rotation}
    turns = [e.peak(c.column("d")) for c in system.coordinates if c.rotation]
    strokes = [max(abs(x) for x in el.stroke) for el in system.elements if el.stroke is not None]
    return judged(moving, system.body.extent, strokes, max(turns, default=0.0))
