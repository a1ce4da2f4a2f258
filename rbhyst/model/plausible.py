"""Magnitudes that betray a unit mistake: an excitation or a body no equipment meets.

A record in cm/s2 declared as g is a 392 g earthquake; vertices in mm make a body of a hundred
metres and a density of grams per cubic metre. Such a deck runs, and its answer is a fiction.
Each check judges a quantity by what bounds it physically, not by one threshold on its peak:
shock pulses of hundreds of g are real, but they last milliseconds, so a support motion is
judged by the velocity it gives the ground (its acceleration integrated over its own
duration: the strongest earthquakes reach 2-4 m/s, shock machines and drop tables some 3-10
m/s), and a force by the velocity it gives the body (its impulse over the mass). The checks
give warnings (rbhyst.errors.ModelWarning), not errors: a deck may mean it.
"""

from __future__ import annotations

import math

import numpy as np

#: a support motion (or a force's impulse per mass) that changes a velocity by more than this
#: (m/s) is beyond any earthquake or shock test: a unit mistake
VELOCITY_LIMIT = 20.0
#: the plausible densities of a body (kg/m3 in space; kg/m2 of its plane outline, a slab of
#: equipment some 0.1-2 m deep): a cabinet of electronics is 200-1000 kg/m3, tungsten 19,300
DENSITY_3D = (1.0, 25_000.0)
DENSITY_2D = (0.5, 50_000.0)
#: what each signal is, by its key
PLACES = {"ag1": "excitation.support.x1", "ag2": "excitation.support.x2", "ag3": "excitation.support.x3",
          "p1": "excitation.force.p1", "p2": "excitation.force.p2", "p3": "excitation.force.p3",
          "m1": "excitation.force.m1", "m2": "excitation.force.m2", "m3": "excitation.force.m3"}
#: the units a value may have been in instead of the declared ones, and their factor to it
LIKELY = {"g": (("cm/s2", 1 / 980.665), ("mm/s2", 1 / 9806.65), ("m/s2", 1 / 9.80665)),
          "m/s2": (("cm/s2", 1e-2), ("mm/s2", 1e-3)),
          "cm/s2": (("mm/s2", 1e-1),),
          "N": (("mN", 1e-3),), "kN": (("N", 1e-3),), "MN": (("kN", 1e-3), ("N", 1e-6)),
          "N m": (("N mm", 1e-3),), "kN m": (("N m", 1e-3), ("N mm", 1e-6))}


def velocity_change(signal) -> float:
    """The largest change of velocity (m/s for an acceleration; N s for a force) the signal makes
    over its span: a sine's velocity amplitude, a pulse's area, a record's integral with its
    linear baseline removed (a record's small offset drifts over a long record)."""
    from rbhyst.model.records import Series
    from rbhyst.model.signals import Pulse, Sine

    if isinstance(signal, Sine):
        return abs(signal.amplitude) / signal.omega if signal.omega > 0 else 0.0
    if isinstance(signal, Series):
        return signal.velocity_change  # (Series.velocity_change: a scaled record's from the record's, once)
    if isinstance(signal, Pulse):
        t = np.linspace(signal.start, signal.end, 2001)
        a = signal(t)
        return float(abs(np.sum(0.5 * (a[1:] + a[:-1]) * np.diff(t))))
    return 0.0  # (a random signal's spectrum is checked against its standard)


def peak(signal) -> float:
    from rbhyst.model.records import Series
    from rbhyst.model.signals import Pulse, Sine

    if isinstance(signal, (Sine, Pulse)):
        return abs(signal.amplitude)
    if isinstance(signal, Series):
        return float(np.max(np.abs(signal.values))) if len(signal.values) else 0.0
    return 0.0


def random_warnings(excitation) -> list[str]:
    """One line per random vibration that its standard's tolerances do not accept
    (rbhyst.model.random_vibration.tolerance): the test it stands for would not be run so."""
    from rbhyst.model.random_vibration import said

    out = []
    for key, place in PLACES.items():
        check = getattr(getattr(excitation, key, None), "tolerance", None)
        if check and check["pass"] is False:
            out.append(f"{place}: {said(check)}")
    return out


def excitation_warnings(excitation, units: dict[str, str], mass: float, inertia: float, size: float) -> list[str]:
    """One line per signal whose velocity change is beyond VELOCITY_LIMIT: a support motion's own,
    a force's impulse over the mass, a moment's over the inertia at the body's size. ``units``:
    each signal's declared units (key -> units, as in the deck)."""
    out = []
    for key, place in PLACES.items():
        signal = getattr(excitation, key, None)
        if signal is None:
            continue
        dv = velocity_change(signal)
        if key.startswith("ag"):
            what, speed = "the ground's velocity", dv
        elif key.startswith("p"):
            what, speed = "the body's velocity (impulse / mass)", dv / mass
        else:
            what, speed = "the body's spin at its size (angular impulse / inertia)", dv / inertia * size
        if not speed > VELOCITY_LIMIT:
            continue
        declared = units.get(key, "")
        hint = ""
        for other, factor in LIKELY.get(declared, ()):
            if speed * factor <= VELOCITY_LIMIT:
                hint = f": a signal in {other} declared as {declared}?"
                break
        shown = f"{peak(signal) / 9.80665:.4g} g" if key.startswith("ag") else f"{peak(signal):.4g} {_si(key)}"
        out.append(f"{place}: peak {shown} changes {what} by {speed:.3g} m/s, beyond any earthquake or shock test "
                   f"(a few m/s){hint or ': check its units and scale'}")
    return out


def _si(key: str) -> str:
    return "N" if key.startswith("p") else "N m"


def density_warning(mass: float, measure: float, dimensions: int) -> list[str]:
    """A body whose mass over its area (plane) or volume (space) is beyond any equipment's."""
    if not measure > 0:
        return []
    lo, hi = DENSITY_3D if dimensions == 3 else DENSITY_2D
    rho = mass / measure
    if lo <= rho <= hi:
        return []
    unit, what = ("kg/m3", "volume") if dimensions == 3 else ("kg/m2", "area")
    guess = ("are the vertices in mm (rbhyst takes m)?" if rho < lo else "is the mass in g (rbhyst takes kg)?")
    return [f"body: {mass:.4g} kg over {'an' if what == 'area' else 'a'} {what} of {measure:.4g} {'m3' if dimensions == 3 else 'm2'} is "
            f"{rho:.3g} {unit}, beyond any equipment's ({lo:g}-{hi:g} {unit}): {guess}"]


def body_measure(body) -> float:
    """The body's area (plane) or volume (space) from its parts, or its outline's."""
    parts = getattr(body, "parts", ())
    if parts:
        return float(sum(getattr(p, "volume", None) or getattr(p, "area", 0.0) for p in parts))
    area = getattr(body, "outline_area", None)
    if area:
        return float(area)
    outline = getattr(body, "outline", None)
    if outline is not None and outline.shape[1] == 3:
        from scipy.spatial import ConvexHull

        try:
            return float(ConvexHull(outline).volume)
        except Exception:  # (an outline that spans no volume: nothing to judge)
            return 0.0
    return 0.0


def signal_units(deck) -> dict[str, str]:
    """Each signal's declared units, by key (PLACES)."""
    ex = deck.excitation
    out = {}
    if ex is None:
        return out
    for key, place in PLACES.items():
        section, axis = place.split(".")[1:]
        spec = getattr(getattr(ex, section, None), axis, None)
        if spec is not None and getattr(spec, "units", None) is not None:
            out[key] = spec.units
    return out


def response_warnings(peaks: dict[str, float], size: float, strokes: list[float], rotation: float) -> list[str]:
    """A response no mounted body survives: G displaced by more than twice the body's size (and
    ten times the largest stroke), or turned by more than a radian."""
    moving = max(peaks.values(), default=0.0)
    stroke = max(strokes, default=0.0)
    out = []
    if moving > 2.0 * size and moving > 10.0 * stroke:
        out.append(f"the body moves by up to {moving:.4g} m, {moving / size:.3g} times its size ({size:.4g} m)"
                   + (f" and {moving / stroke:.3g} times the largest stroke" if stroke > 0 else "")
                   + ": no mounted body does; check the excitation's units and scale")
    if rotation > 1.0:
        out.append(f"the body turns by up to {rotation:.4g} rad ({math.degrees(rotation):.4g} degrees): beyond what "
                   "equipment on mounts survives; check the excitation's units and scale")
    return out
