"""Two-column text tables of a curve against frequency (a required response spectrum, a PSD),
read with one-line errors naming the file and line."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.errors import InputError
from rbhyst.files.textfiles import is_number, read_text
from rbhyst.files.units import header_labels


@dataclass(frozen=True)
class Curve:
    """Two columns of a text table: x ascending, y, the header's labels and each row's line."""

    x: np.ndarray
    y: np.ndarray
    labels: list[str]
    header_line: int | None
    lines: list[int]


def read_curve(path: Path, what: str) -> Curve:
    """A two-column table (commas, semicolons or spaces; '#' comments; one header row), x
    strictly increasing and positive, y positive; problems name the file and line."""
    lines = read_text(path).splitlines()
    rows, where, labels, header_line = [], [], [], None
    for j, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        toks = [t for t in text.replace(";", ",").replace(",", " ").split()]
        if not rows and header_line is None and not is_number(toks[0]):
            header_line, labels = j, header_labels(text)
            continue
        if len(toks) != 2:
            raise InputError(f"{path}:{j}: {len(toks)} columns; {what} has two (frequency, value)")
        try:
            row = [float(t) for t in toks]
        except ValueError:
            bad = next(t for t in toks if not is_number(t))
            raise InputError(f"{path}:{j}: {bad!r} is not a number") from None
        if not all(math.isfinite(v) for v in row):
            raise InputError(f"{path}:{j}: not a finite number")
        if row[0] <= 0.0 or row[1] <= 0.0:
            raise InputError(f"{path}:{j}: the frequency and the value must be positive (log-log interpolation)")
        if rows and row[0] <= rows[-1][0]:
            raise InputError(f"{path}:{j}: the frequency {row[0]:g} Hz does not increase (previous {rows[-1][0]:g} Hz)")
        rows.append(row)
        where.append(j)
    if len(rows) < 2:
        raise InputError(f"{path}: {what} needs at least two rows of numbers, found {len(rows)}")
    data = np.array(rows)
    return Curve(data[:, 0], data[:, 1], labels, header_line, where)
