"""The files of a run: time_history.csv streamed chunk by chunk (a run of any length needs
one chunk of rows in memory), summary.json, spectra.csv."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rbhyst.solve.result import Result

if TYPE_CHECKING:  # pragma: no cover
    from rbhyst.solve.located import LocatedSpectra


class CsvWriter:
    """time_history.csv, written chunk by chunk: 10 significant digits, one header row."""

    def __init__(self, path: Path, columns: tuple[str, ...]):
        from rbhyst.results.csvtext import RowsText

        self._format = RowsText()
        self.path = Path(path)
        self._fh = open(self.path, "wb")
        self._fh.write((",".join(columns) + "\n").encode())

    def add(self, rows: np.ndarray) -> None:
        self._fh.write(self._format(rows))  # (made row-major there; a view of its buffer, written at once)

    def close(self) -> None:
        self._fh.close()


def write_csv(result: Result, path: Path) -> None:
    """The kept table as time_history.csv."""
    w = CsvWriter(path, result.columns)
    try:
        w.add(result._rows())
    finally:
        w.close()


def write_summary(result: Result, path: Path) -> None:
    Path(path).write_text(json.dumps(result.summary(), indent=2) + "\n")


def write_spectra_csv(spectra: "LocatedSpectra", path: Path) -> None:
    from rbhyst.solve.located import SPECTRA_COLUMNS  # (the spectra's kernels only where there are spectra)

    labels, numbers = spectra.table()
    lines = [",".join(SPECTRA_COLUMNS)]
    lines += [f"{loc},{direction}," + ",".join(f"{v:.10g}" for v in row)
              for (loc, direction), row in zip(labels, numbers)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
