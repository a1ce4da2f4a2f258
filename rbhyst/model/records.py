"""Reading excitation histories: PEER NGA .AT2, two columns (time,value), one column + dt.

Every reader returns a :class:`RecordFile`: a uniformly sampled :class:`Series` in the
file's own value units with its time in seconds, and the value unit the file declares (see
:mod:`rbhyst.files.units`). Anything it cannot read unambiguously is an
:class:`~rbhyst.errors.InputError` naming the file and line.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.files.units import TIME_TO_S, Declared, at2_declarations, header_labels, kind_article, label_unit
from rbhyst.files.textfiles import is_number, read_text

#: NPTS/DT as in "NPTS=  4000, DT= .01000 SEC" (NGA) or "4000  0.0100  NPTS, DT" (older PEER)
_AT2_NEW = re.compile(r"NPTS\s*=\s*(\d+)\s*[,;]?\s*DT\s*=\s*([-+]?[\d.]+(?:[eE][-+]?\d+)?)", re.I)
_AT2_OLD = re.compile(r"^\s*(\d+)\s+([-+]?[\d.]+(?:[eE][-+]?\d+)?)\s+NPTS", re.I)


@dataclass(frozen=True)
class Series:
    """Samples ``values[i]`` at ``t0 + i * dt``."""

    t0: float
    dt: float
    values: np.ndarray

    @property
    def duration(self) -> float:
        return self.t0 + (len(self.values) - 1) * self.dt

    @property
    def step(self) -> float:
        return self.dt

    @property
    def start(self) -> float:
        return self.t0

    @property
    def end(self) -> float:
        return self.duration

    @functools.cached_property
    def times(self) -> np.ndarray:
        return self.t0 + self.dt * np.arange(len(self.values))

    def acts_before(self, t_end: float) -> bool:
        return bool(np.any(self.values[self.times < t_end] != 0.0))

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """Linear interpolation; zero outside the record (free vibration after it ends)."""
        return np.interp(t, self.times, self.values, left=0.0, right=0.0)

    @functools.cached_property
    def velocity_change(self) -> float:
        """The largest change of velocity the samples make over their span (value units times
        seconds): their trapezoidal integral with its linear baseline removed (a record's small
        offset drifts over a long record)."""
        a = np.asarray(self.values, dtype=float)
        if len(a) < 2:
            return 0.0
        v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * self.dt)])
        t = np.arange(len(v), dtype=float)
        v = v - np.polyval(np.polyfit(t, v, 1), t)
        return float(np.max(np.abs(v)))


@dataclass(frozen=True)
class ScaledSeries(Series):
    """A record's samples times ``factor`` (its units' to SI, times the deck's scale): a record is
    read once per process and scaled per run, so what is linear in its samples is taken from
    the record itself (``of``), once."""

    of: Series = field(kw_only=True)
    factor: float = field(kw_only=True)

    @functools.cached_property
    def velocity_change(self) -> float:
        return abs(self.factor) * self.of.velocity_change


@dataclass(frozen=True)
class RecordFile:
    """What a record file holds: its samples, the value unit it declares, notes for the run."""

    series: Series
    declared: Declared | None = None
    notes: tuple[str, ...] = ()


def _number(tok: str, where: str) -> float:
    try:
        x = float(tok)
    except ValueError:
        raise InputError(f"{where}: {tok!r} is not a number") from None
    if not math.isfinite(x):
        raise InputError(f"{where}: {tok!r} is not a finite number")
    return x


def read_at2(path: Path) -> RecordFile:
    """A PEER NGA .AT2 file; the NPTS/DT line is found by pattern, not by position, and the
    units by what the lines above it say."""
    lines = _read_lines(path)
    for i, line in enumerate(lines[:20]):
        m = _AT2_NEW.search(line) or _AT2_OLD.search(line)
        if m:
            npts, dt = int(m.group(1)), float(m.group(2))
            break
    else:
        raise InputError(f"{path}: no 'NPTS=..., DT=...' line in the AT2 header")
    if npts < 2 or not dt > 0.0:
        raise InputError(f"{path}:{i + 1}: header gives NPTS={npts}, DT={dt}: need NPTS >= 2 and DT > 0")
    values = []
    for j, line in enumerate(lines[i + 1:], start=i + 2):
        values.extend(_number(tok, f"{path}:{j}") for tok in line.split())
    if len(values) != npts:
        raise InputError(f"{path}: the header says NPTS={npts} but the file holds {len(values)} values")
    return RecordFile(Series(0.0, dt, np.array(values)), _at2_units(path, lines[:i]))


def _at2_units(path: Path, header: list[str]) -> Declared | None:
    """The one value unit the AT2 header declares; two different ones are an error."""
    found = at2_declarations(header)
    if not found:
        return None
    (i, text, unit), *rest = found
    for j, other_text, other in rest:
        if other != unit:
            raise InputError(f"{path}:{j + 1}: the header declares both {text!r} ({unit.name}, line {i + 1}) "
                             f"and {other_text!r} ({other.name})")
    return Declared(unit, text, f"{path}:{i + 1}")


def read_table(path: Path, dt: float | None = None) -> RecordFile:
    """Two columns ``time,value`` (uniform time step) or one column of values with ``dt``.

    Commas, semicolons or white space separate columns; one header row is allowed, and the
    units its labels declare are read: a time column in ms, us, min ... is converted to s.
    """
    lines = _read_lines(path)
    data, first, header = _fast_table(lines)
    if data is None:  # something to say about a line: the careful reader finds it
        data, first, header = _careful_table(lines, path)
    ncol = data.shape[1]
    if ncol == 1:
        if dt is None:
            raise InputError(f"{path}: one column of values needs `dt` in the deck")
        declared, _, _ = _column_units(path, first, header, ncol)
        return RecordFile(Series(0.0, dt, data[:, 0]), declared)
    if ncol != 2:
        comma = next((k for k, line in enumerate(lines) if re.fullmatch(r"\s*-?\d+,\d+(\s*;\s*-?\d+,\d+(e[-+]?\d+)?)+\s*",
                                                                        line, re.IGNORECASE)), None)
        if comma is not None:
            raise InputError(f"{path}:{comma + 1}: {lines[comma].strip()!r} looks like a spreadsheet's export with decimal "
                             "commas and semicolons between columns: rbhyst reads decimal points; export it with '.' "
                             "as the decimal separator")
        raise InputError(f"{path}: expected one column (with dt) or two (time, value), found {ncol}")
    if dt is not None:
        raise InputError(f"{path}: has a time column; leave `dt` out of the deck")
    declared, label, unit = _column_units(path, first, header, ncol)
    t = data[:, 0]
    notes = ()
    if unit != "s":
        mul, div = TIME_TO_S[unit]
        t = t * mul / div
        notes = (f"time column {label!r} converted from {unit} to s",)
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        raise InputError(f"{path}: the time column does not increase at row {k + 2}")
    step = (t[-1] - t[0]) / (len(t) - 1)
    if np.max(np.abs(steps - step)) > 1e-6 * step + 1e-12 * abs(t[-1]):
        k = int(np.argmax(np.abs(steps - step)))
        raise InputError(
            f"{path}: the time step is not uniform (row {k + 2}: {steps[k]:.6g} s, mean {step:.6g} s)"
        )
    return RecordFile(Series(float(t[0]), float(step), data[:, 1]), declared, notes)


def _column_units(path: Path, line: int | None, header: str, ncol: int) -> tuple[Declared | None, str, str]:
    """The value unit a table's header declares, and the time column's label and unit (s
    where it declares none).

    A time column must be in a time unit rbhyst converts; a header whose labels do not match
    the columns one to one declares nothing, unless it names a unit (then it is ambiguous).
    """
    labels = header_labels(header) if line is not None else []
    units = [label_unit(lb) for lb in labels]
    if len(labels) != ncol:
        if any(u is not None for _, u in units):
            n = len(labels)
            raise InputError(f"{path}:{line}: the header names {n} column{'s' * (n != 1)} but the rows hold "
                             f"{ncol}: cannot tell which unit belongs to which column")
        return None, "", "s"
    value_unit = units[-1][1]
    declared = None if value_unit is None else Declared(value_unit, labels[-1], f"{path}:{line}")
    if ncol == 1:
        return declared, "", "s"
    (token, time_unit), label = units[0], labels[0]
    if token is None:
        return declared, label, "s"
    if time_unit is None or time_unit.kind != "time":
        what = "not a time unit" if time_unit is None else f"{kind_article(time_unit.kind)} unit"
        raise InputError(f"{path}:{line}: the time column {label!r}: {token!r} is {what}; "
                         f"use one of {', '.join(TIME_TO_S)}")
    return declared, label, time_unit.name


def read_record(path: Path, dt: float | None = None) -> RecordFile:
    """Pick the reader by extension: .at2 or any text table.

    A file already read in this process, unchanged since (same size and modification time),
    is not read again: a sweep or a script running one deck many times reads its records once.
    """
    try:
        st = Path(path).stat()
    except OSError:
        return _read_record(path, dt)  # the reader says what is wrong with it
    return _cached_record(str(path), st.st_mtime_ns, st.st_size, dt)


@functools.lru_cache(maxsize=64)
def _cached_record(path: str, mtime_ns: int, size: int, dt: float | None) -> RecordFile:
    record = _read_record(Path(path), dt)
    record.series.values.flags.writeable = False  # shared by every run that reads the file
    return record


def _read_record(path: Path, dt: float | None) -> RecordFile:
    if path.suffix.lower() == ".at2":
        if dt is not None:
            raise InputError(f"{path}: an AT2 file gives its own DT; leave `dt` out of the deck")
        return read_at2(path)
    return read_table(path, dt)


def _rows_of(lines: list[str]):
    """(line number, text without comments) of every non-empty line."""
    for j, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if text:
            yield j, text


_SEPARATORS = re.compile(r"[,;\s]+")


def _tokens(text: str) -> list[str]:
    """The numbers of a line or lines as text: what splitting at every run of _SEPARATORS gives,
    by plain string methods (a regular expression per line cost a record of 4,000 lines ~10 ms)."""
    return text.replace(",", " ").replace(";", " ").split()


def _fast_table(lines: list[str]):
    """(data, header line, header) of a well-formed table in one numpy conversion, or (None, ...)."""
    body, first, header = [], None, ""
    rows = _rows_of(lines)
    for j, text in rows:
        if first is None and not is_number(_SEPARATORS.split(text, 1)[0]):
            first, header = j, text
            continue
        body.append(text)
        break
    body.extend(text for _, text in rows)
    if len(body) < 2:
        return None, first, header
    ncol = len(_tokens(body[0]))
    try:
        data = np.array(_tokens(" ".join(body)), dtype=float)
    except ValueError:
        return None, first, header
    if ncol == 0 or data.size != ncol * len(body) or any(len(_tokens(b)) != ncol for b in body[:: max(1, len(body) // 64)]) \
            or not np.all(np.isfinite(data)):
        return None, first, header
    data = data.reshape(len(body), ncol)
    return data, first, header


def _careful_table(lines: list[str], path: Path):
    """The same, row by row, raising an InputError that names the file and line of a problem."""
    rows: list[list[float]] = []
    first = None
    header = ""
    for j, text in _rows_of(lines):
        toks = [t for t in _SEPARATORS.split(text) if t]
        if not rows and first is None and not is_number(toks[0]):
            first, header = j, text  # a header row
            continue
        row = [_number(t, f"{path}:{j}") for t in toks]
        if rows and len(row) != len(rows[0]):
            raise InputError(f"{path}:{j}: {len(row)} columns where earlier rows have {len(rows[0])}")
        rows.append(row)
    if len(rows) < 2:
        raise InputError(f"{path}: needs at least two rows of numbers, found {len(rows)}")
    return np.array(rows), first, header


def read_series(path: Path, dt: float | None = None) -> Series:
    """The samples of :func:`read_record`, time in seconds and values in the file's units."""
    return read_record(path, dt).series


def _read_lines(path: Path) -> list[str]:
    text = read_text(path)
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise InputError(f"{path}: the file is empty")
    return lines
