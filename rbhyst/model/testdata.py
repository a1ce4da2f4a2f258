"""Measured force-displacement data: a CSV file with units in its header (or given as flags).

The file has a header row naming its columns with units, e.g. ``u_mm,f_kN`` or
``displacement [m],force [N]`` (``time``/``t`` columns are allowed and ignored), then one
row per sample. Units are never guessed: a column without them needs ``u_units`` /
``f_units``. Comment lines start with ``#``. Anything that cannot be read unambiguously
(NaN, a non-numeric cell, a single column, missing units, less than one cycle) is an
:class:`~rbhyst.errors.InputError` with one line naming the file and, where it helps,
the line.

Everything returned is in SI: metres and newtons.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.files.textfiles import is_number, read_text

DISPLACEMENT_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "MN": 1e6, "lbf": 4.4482216152605, "kip": 4448.2216152605}

_U_NAMES = {"u", "d", "x", "disp", "displacement", "deformation", "deflection", "stroke"}
_F_NAMES = {"f", "force", "load", "p", "fr"}
_T_NAMES = {"t", "time"}

#: a reversal counts towards "one cycle" only if the displacement retreats by this
#: fraction of its range, so that noise in a measured displacement does not count
CYCLE_TOL = 0.05


@dataclass(frozen=True)
class LoopData:
    """A measured loop in SI units: displacement ``u`` [m] and force ``f`` [N]."""

    name: str  # the file name, for reports (no folders)
    u: np.ndarray
    f: np.ndarray
    u_units: str  # as read, for reports
    f_units: str


def _unit(table: dict, token: str) -> str | None:
    for key in table:
        if token.lower() == key.lower():
            return key
    return None


def _split_column(label: str) -> tuple[str, str | None]:
    """``'force [kN]'`` / ``'force (kN)'`` / ``'f_kN'`` -> (``'force'``, ``'kN'``)."""
    label = label.strip().strip('"').strip("'").strip()
    m = re.fullmatch(r"(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]", label)
    if m:
        return m.group(1).strip().lower(), m.group(2)
    if "_" in label:
        head, tail = label.rsplit("_", 1)
        if _unit(DISPLACEMENT_UNITS, tail) or _unit(FORCE_UNITS, tail) or tail.lower() in ("s", "sec"):
            return head.strip().lower(), tail
    return label.lower(), None


def _delimiter(header: str) -> str | None:
    for d in (",", ";", "\t"):
        if d in header:
            return d
    return None  # whitespace


def _cells(line: str, delim: str | None) -> list[str]:
    return [c.strip() for c in (line.split(delim) if delim else line.split())]


def significant_reversals(u: np.ndarray, tol: float = CYCLE_TOL) -> np.ndarray:
    """Indices where the displacement turns back by more than ``tol`` of its range.

    A turning point is confirmed once ``u`` has retreated from the running extreme
    by ``tol * (max u - min u)``; smaller wiggles (noise) are ignored.
    """
    u = np.asarray(u, dtype=float)
    if u.size < 3:
        return np.zeros(0, dtype=int)
    band = tol * float(np.ptp(u))
    if band <= 0.0:
        return np.zeros(0, dtype=int)
    out = []
    direction = 0  # not yet known: the first move larger than the band sets it
    lo = hi = ext = 0
    for i in range(1, u.size):
        if direction == 0:
            lo = i if u[i] < u[lo] else lo
            hi = i if u[i] > u[hi] else hi
            if u[i] - u[lo] > band:
                direction, ext = 1, i
            elif u[hi] - u[i] > band:
                direction, ext = -1, i
        elif direction == 1:
            if u[i] >= u[ext]:
                ext = i
            elif u[ext] - u[i] > band:
                out.append(ext)
                direction, ext = -1, i
        else:
            if u[i] <= u[ext]:
                ext = i
            elif u[i] - u[ext] > band:
                out.append(ext)
                direction, ext = 1, i
    return np.asarray(out, dtype=int)


def read_loop_data(path: str | Path, u_units: str | None = None, f_units: str | None = None) -> LoopData:
    """Read a measured force-displacement CSV; raise InputError with one line on any problem."""
    path = Path(path)
    text = read_text(path, encoding="utf-8-sig")

    if u_units is not None and not _unit(DISPLACEMENT_UNITS, u_units):
        raise InputError(f"--u-units: unknown displacement unit {u_units!r}; "
                         f"use one of {', '.join(DISPLACEMENT_UNITS)}")
    if f_units is not None and not _unit(FORCE_UNITS, f_units):
        raise InputError(f"--f-units: unknown force unit {f_units!r}; use one of {', '.join(FORCE_UNITS)}")

    rows = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: no data")
    head_no, header = rows[0]
    delim = _delimiter(header)
    labels = _cells(header, delim)
    if all(is_number(c) for c in labels):
        # no header row: allowed only when both units come from the flags
        if u_units is None or f_units is None:
            raise InputError(f"{path}: line {head_no}: no header with units (e.g. 'u_mm,f_kN' or "
                             "'displacement [m],force [N]'); add one or give --u-units and --f-units")
        labels = ["u", "f"] + [f"column {k}" for k in range(3, len(labels) + 1)]
        body = rows
    else:
        body = rows[1:]
    if len(labels) < 2:
        raise InputError(f"{path}: line {head_no}: one column; need displacement and force columns")

    parts = [_split_column(c) for c in labels]
    iu, iff = _pick_columns(path, head_no, labels, parts)
    uu = _resolve_units(path, labels[iu], parts[iu][1], u_units, DISPLACEMENT_UNITS, "--u-units", "displacement")
    fu = _resolve_units(path, labels[iff], parts[iff][1], f_units, FORCE_UNITS, "--f-units", "force")

    n_cols = len(labels)
    data = np.empty((len(body), 2))
    for k, (n, line) in enumerate(body):
        cells = _cells(line, delim)
        if len(cells) != n_cols:
            raise InputError(f"{path}: line {n}: {len(cells)} values, the header has {n_cols} columns")
        for j, col in enumerate((iu, iff)):
            tok = cells[col]
            try:
                x = float(tok)
            except ValueError:
                what = "an empty cell" if tok == "" else f"{tok!r} is not a number"
                raise InputError(f"{path}: line {n}, column {labels[col]!r}: {what}") from None
            if not math.isfinite(x):
                raise InputError(f"{path}: line {n}, column {labels[col]!r}: {tok!r} is not a finite number")
            data[k, j] = x

    u = data[:, 0] * DISPLACEMENT_UNITS[uu]
    f = data[:, 1] * FORCE_UNITS[fu]
    n_rev = len(significant_reversals(u))
    if n_rev < 2:
        raise InputError(
            f"{path}: {len(u)} samples with {n_rev} reversal{'s' if n_rev != 1 else ''} of the displacement: "
            "less than one cycle (a loop needs the displacement to go out, back and out again)")
    return LoopData(name=path.name, u=u, f=f, u_units=uu, f_units=fu)


def _pick_columns(path, line_no, labels, parts) -> tuple[int, int]:
    names = [p[0] for p in parts]
    iu = [k for k, nm in enumerate(names) if nm in _U_NAMES or nm.startswith("displacement")]
    iff = [k for k, nm in enumerate(names) if nm in _F_NAMES or nm.startswith("force")]
    if iu and iff:
        return iu[0], iff[0]
    others = [k for k, nm in enumerate(names) if nm not in _T_NAMES]
    if not iu and not iff and len(others) == 2:
        return others[0], others[1]  # two unnamed columns: displacement, then force
    raise InputError(f"{path}: line {line_no}: cannot tell the displacement and force columns in "
                     f"{', '.join(repr(x) for x in labels)}; name them e.g. 'u_mm,f_kN'")


def _resolve_units(path, label, from_header, from_flag, table, flag, what) -> str:
    hdr = _unit(table, from_header) if from_header is not None else None
    if from_header is not None and hdr is None:
        raise InputError(f"{path}: column {label!r}: unknown {what} unit {from_header!r}; "
                         f"use one of {', '.join(table)}")
    flg = _unit(table, from_flag) if from_flag is not None else None
    if hdr and flg and hdr != flg:
        raise InputError(f"{path}: column {label!r} is in {hdr} but {flag} says {flg}")
    unit = hdr or flg
    if unit is None:
        raise InputError(f"{path}: column {label!r}: no {what} units; write them in the header "
                         f"(e.g. '{label}_{next(iter(table))}') or give {flag}")
    return unit
