"""What a record file declares about its units: AT2 header phrases and table column labels.

A declaration counts only where it is unambiguous: a unit inside brackets or parentheses
ending a column label (``a [m/s2]``, ``t (ms)``), a unit suffix after ``_`` (``acc_g``,
``acceleration_m_s2``, ``m3_kN_m``, ``time_ms``), or in an AT2 header a phrase such as
``UNITS OF G`` or ``IN CM/S/S`` or a compound unit (``CM/SEC/SEC``, ``GAL``). Anything else
declares nothing, and the deck's units apply. Pure functions: the readers in
:mod:`rbhyst.model.records` call them and report where the declaration stands.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rbhyst.errors import InputError


@dataclass(frozen=True)
class Unit:
    name: str  # as the deck spells it where the deck knows it: "g", "m/s2", "kN m", "ms"
    kind: str  # acceleration, force, moment, velocity, length or time


@dataclass(frozen=True)
class Declared:
    """A unit a file declares, the text that declares it and where (``file:line``)."""

    unit: Unit
    text: str
    where: str


#: time units a time column may be in, as (multiplier, divisor) to seconds: a division by an
#: exact integer keeps t_ms / 1000 equal to the same time written in seconds
TIME_TO_S = {"s": (1, 1), "ms": (1, 1000), "us": (1, 10**6), "ns": (1, 10**9), "min": (60, 1), "hr": (3600, 1)}

_TIME = {
    "s": "s", "sec": "s", "secs": "s", "second": "s", "seconds": "s",
    "ms": "ms", "msec": "ms", "millisecond": "ms", "milliseconds": "ms",
    "us": "us", "usec": "us", "microsecond": "us", "microseconds": "us",
    "ns": "ns", "nsec": "ns", "nanosecond": "ns", "nanoseconds": "ns",
    "min": "min", "mins": "min", "minute": "min", "minutes": "min",
    "hr": "hr", "hrs": "hr", "hour": "hr", "hours": "hr",
}
_LENGTH = "(m|cm|mm|in|ft)"
_PER_S2 = re.compile(rf"{_LENGTH}(?:/s2|/s/s|s-2|\*s-2|\.s-2|ps2|pss|_s2|_s_s)")
_PER_S = re.compile(rf"{_LENGTH}(?:/s|s-1|\*s-1|\.s-1|ps|_s)")
# where case tells units apart (N and n, Nm and nm, MN and mN) the spelling must match exactly
_FORCE = {"N": "N", "kN": "kN", "KN": "kN", "MN": "MN"}
_FORCE_ANY_CASE = {"lbf": "lbf", "kip": "kip", "kips": "kip"}
_MOMENT = re.compile(r"(N|kN|KN)[*._-]?m")


def _compact(token: str) -> str:
    """Spacing and exponent spellings removed: 'cm/s^2' -> 'cm/s2', 'kN m' -> 'kNm'."""
    t = token.strip().replace("²", "2").replace("⁻", "-").replace("µ", "u").replace("μ", "u")
    t = t.replace("·", "*").replace("**", "").replace("^", "")
    return re.sub(r"\s+", "", t)


def unit_of(token: str) -> Unit | None:
    """The unit ``token`` spells, or None when it is not one rbhyst can tell for sure."""
    t = _compact(token)
    if not t:
        return None
    low = t.lower().replace("/sec", "/s")
    if low == "g":
        return Unit("g", "acceleration")
    if low in ("gal", "gals"):
        return Unit("cm/s2", "acceleration")
    if low == "mg":  # milli-g
        return Unit("mg", "acceleration")
    if m := _PER_S2.fullmatch(low):
        return Unit(f"{m.group(1)}/s2", "acceleration")
    if m := _PER_S.fullmatch(low):
        return Unit(f"{m.group(1)}/s", "velocity")
    if low in _TIME:
        return Unit(_TIME[low], "time")
    if t in _FORCE or low in _FORCE_ANY_CASE:
        return Unit(_FORCE.get(t) or _FORCE_ANY_CASE[low], "force")
    if m := _MOMENT.fullmatch(t):
        return Unit(f"{_FORCE[m.group(1)]} m", "moment")
    if low in ("m", "cm", "mm"):
        return Unit(low, "length")
    return None


# ---------------------------------------------------------------- table column labels

_BRACKETED = re.compile(r"(.*?)\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*")
#: one label of a header separated by white space: a name, then any bracket groups
_SPACED_LABEL = re.compile(r"[^\s\[(]+(?:\s*[\[(][^\])]*[\])])*|[\[(][^\])]*[\])]")


def header_labels(header: str) -> list[str]:
    """The column labels of a header row: split at commas, semicolons or tabs, else at spaces
    (keeping ``t [s]`` together)."""
    if re.search(r"[,;\t]", header):
        return [c.strip().strip("\"'").strip() for c in re.split(r"[,;\t]", header.strip())]
    return [c.strip() for c in _SPACED_LABEL.findall(header)]


def label_unit(label: str) -> tuple[str | None, Unit | None]:
    """The token in a label's unit position and the unit it spells.

    ``'a [cm/s^2]'`` -> ('cm/s^2', cm/s2); ``'acceleration_m_s2'`` -> ('m_s2', m/s2);
    ``'t [fortnight]'`` -> ('fortnight', None): a bracket is a unit position even when its
    content is unknown; ``'acc_x'`` -> (None, None): a suffix counts only if it is a unit.
    """
    m = _BRACKETED.fullmatch(label.strip())
    if m:
        return m.group(2), unit_of(m.group(2))
    parts = label.strip().split("_")
    for n in range(min(3, len(parts) - 1), 0, -1):  # longest first: kN_m before m
        tail = "_".join(parts[-n:])
        unit = unit_of(tail)
        if unit is not None:
            return tail, unit
    return None, None


# ---------------------------------------------------------------- AT2 headers

_TOKEN = r"([A-Za-z][A-Za-z0-9/*^.²-]*)"
_PHRASES = [re.compile(p, re.I) for p in (
    rf"\bUNITS?\s+OF\s+{_TOKEN}", rf"\bUNITS?\s*[:=]\s*{_TOKEN}", rf"\bIN\s+{_TOKEN}",
)]
#: what the AT2 layout carries (acceleration; velocity and displacement in its .VT2/.DT2
#: siblings): a lone 'S' or 'N' in a station name is no declaration
_AT2_KINDS = ("acceleration", "velocity", "length")


def at2_declarations(lines: list[str]) -> list[tuple[int, str, Unit]]:
    """(line index, text, unit) of the units the header lines declare, in reading order.

    Phrases come first: ``UNITS OF G``, ``UNITS: CM/S/S``, ``IN G``; a bare ``G`` or
    ``CM`` counts only in one. Where there is none, a compound unit (``CM/SEC/SEC``, ``M/S2``)
    or ``GAL`` anywhere counts (a header explaining its unit, "UNITS OF G (980.665 CM/S/S)",
    still declares g).
    """
    phrases, loose = [], []
    for i, line in enumerate(lines):
        for pattern in _PHRASES:
            for m in pattern.finditer(line):
                unit = unit_of(m.group(1).rstrip(".-"))
                if unit is not None and unit.kind in _AT2_KINDS:
                    phrases.append((i, m.start(), m.group(0).rstrip(".-").strip(), unit))
        for m in re.finditer(_TOKEN, line):
            token = m.group(1).rstrip(".-")
            unit = unit_of(token) if "/" in token or token.lower() in ("gal", "gals") else None
            if unit is not None and unit.kind in _AT2_KINDS:
                loose.append((i, m.start(), token, unit))
    return [(i, text, unit) for i, _, text, unit in sorted(phrases or loose, key=lambda f: f[:2])]


# ---------------------------------------------------------------- the check against the deck

def kind_article(kind: str) -> str:
    """'an acceleration', 'a force' ..."""
    return ("an " if kind[0] in "aeiou" else "a ") + kind


def check_declared(declared: Declared | None, deck_units: str) -> None:
    """An InputError where the file's declared unit contradicts the deck's ``units``."""
    if declared is None:
        return
    deck = unit_of(deck_units)
    unit = declared.unit
    if deck is not None and unit.name == deck.name and unit.kind == deck.kind:
        return
    if deck is not None and unit.kind != deck.kind:
        what, says = f"{unit.name}, {kind_article(unit.kind)}", f" ({kind_article(deck.kind)})"
    else:
        what, says = unit.name, ""
    raise InputError(f"{declared.where}: the header declares {declared.text!r} ({what}) "
                     f'but the deck says units = "{deck_units}"{says}')
