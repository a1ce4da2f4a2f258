"""Reading excitation histories: PEER NGA .AT2, two columns (time,value), one column + dt.

Every reader returns a uniformly sampled :class:`Series` in the file's own units;
anything it cannot read unambiguously is an :class:`~rbhyst.errors.InputError`
naming the file and line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError
from .textfiles import is_number, read_text

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

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """Linear interpolation; zero outside the record (free vibration after it ends)."""
        times = self.t0 + self.dt * np.arange(len(self.values))
        return np.interp(t, times, self.values, left=0.0, right=0.0)


def _number(tok: str, where: str) -> float:
    try:
        x = float(tok)
    except ValueError:
        raise InputError(f"{where}: {tok!r} is not a number") from None
    if not math.isfinite(x):
        raise InputError(f"{where}: {tok!r} is not a finite number")
    return x


def read_at2(path: Path) -> Series:
    """A PEER NGA .AT2 file; the NPTS/DT line is found by pattern, not by position."""
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
    return Series(0.0, dt, np.array(values))


def read_table(path: Path, dt: float | None = None) -> Series:
    """Two columns ``time,value`` (uniform time step) or one column of values with ``dt``.

    Commas, semicolons or white space separate columns; one header row is allowed.
    """
    rows: list[list[float]] = []
    first = None
    for j, line in enumerate(_read_lines(path), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        toks = [t for t in re.split(r"[,;\s]+", text) if t]
        if not rows and first is None and not is_number(toks[0]):
            first = j  # a header row
            continue
        row = [_number(t, f"{path}:{j}") for t in toks]
        if rows and len(row) != len(rows[0]):
            raise InputError(f"{path}:{j}: {len(row)} columns where earlier rows have {len(rows[0])}")
        rows.append(row)
    if len(rows) < 2:
        raise InputError(f"{path}: needs at least two rows of numbers, found {len(rows)}")
    data = np.array(rows)
    ncol = data.shape[1]
    if ncol == 1:
        if dt is None:
            raise InputError(f"{path}: one column of values needs `dt` in the deck")
        return Series(0.0, dt, data[:, 0])
    if ncol != 2:
        raise InputError(f"{path}: expected one column (with dt) or two (time, value), found {ncol}")
    if dt is not None:
        raise InputError(f"{path}: has a time column; leave `dt` out of the deck")
    t = data[:, 0]
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
    return Series(float(t[0]), float(step), data[:, 1])


def read_series(path: Path, dt: float | None = None) -> Series:
    """Pick the reader by extension: .at2 or any text table."""
    if path.suffix.lower() == ".at2":
        if dt is not None:
            raise InputError(f"{path}: an AT2 file gives its own DT; leave `dt` out of the deck")
        return read_at2(path)
    return read_table(path, dt)


def _read_lines(path: Path) -> list[str]:
    text = read_text(path)
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise InputError(f"{path}: the file is empty")
    return lines
