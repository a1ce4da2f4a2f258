"""The files of a run: time_history.csv streamed chunk by chunk (a run of any length needs
one chunk of rows in memory), summary.json, spectra.csv."""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rbhyst.solve.result import Result

if TYPE_CHECKING:  # pragma: no cover
    from rbhyst.solve.located import LocatedSpectra


class CsvWriter:
    """time_history.csv, written chunk by chunk: 10 significant digits, one header row.

    ``CsvWriter(path)`` is what a run is given; the run calls it with its columns to start the
    file (a run that is repeated, as tolerance mode's ladder does, starts it over), then
    ``add(rows)`` for every chunk and ``close()``. Each chunk's text is written by a thread of its
    own while the caller goes on with the next chunk, the error estimate and the figures: most
    of a write is the system finding fresh pages for the file, which holds no lock of Python's
    (the seed deck's 21 MB take 40-150 ms of it, as long as all the rest of the run). Two text
    buffers take turns, so that one chunk is formatted while the one before is written.
    ``close()`` leaves the file to close after its last write; ``wait()`` returns once it has,
    and raises what a write raised. Whoever gave the run a CsvWriter waits for it before the
    folder is put in place or removed.
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        self._text = None
        self._fh = None
        self._last: threading.Thread | None = None
        self._error: BaseException | None = None

    def __call__(self, columns: tuple[str, ...]) -> "CsvWriter":
        from rbhyst.results.csvtext import RowsText

        self.wait()
        if self._text is None:
            self._text = RowsText()
        self._writing: list[threading.Thread | None] = [None, None]  # the write that reads each text
        self._chunks = 0
        self._fh = open(self.path, "wb")
        self._fh.write((",".join(columns) + "\n").encode())
        return self

    def add(self, rows: np.ndarray) -> None:
        i = self._chunks % 2
        self._chunks += 1
        self._join(self._writing[i])  # (its text buffer is free again)
        text = self._text(rows, slot=i)  # (a view of that buffer)
        self._writing[i] = self._after_last(self._fh.write, text)

    def close(self) -> None:
        """The file closes after its last write, whether or not a write failed; wait() for it."""
        if self._fh is not None:
            self._after_last(self._fh.close, always=True)
            self._fh = None

    def wait(self) -> None:
        """Return once every write queued so far has ended; raise what one of them raised."""
        self._join(self._last)

    def _after_last(self, work, *args, always: bool = False) -> threading.Thread:
        before = self._last

        def step():
            if before is not None:
                before.join()
            if self._error is None or always:
                try:
                    work(*args)
                except BaseException as exc:  # (raised in the caller's thread by wait() or the next add())
                    self._error = self._error or exc

        self._last = threading.Thread(target=step, name="time_history.csv", daemon=True)
        self._last.start()
        return self._last

    def _join(self, thread: threading.Thread | None) -> None:
        if thread is not None:
            thread.join()
        if self._error is not None:
            raise self._error


def write_csv(result: Result, path: Path) -> None:
    """The kept table as time_history.csv."""
    w = CsvWriter(path)(result.columns)
    try:
        w.add(result._rows())
    finally:
        w.close()
        w.wait()


def write_summary(result: Result, path: Path) -> None:
    Path(path).write_text(json.dumps(result.summary(), indent=2) + "\n")


def write_spectra_csv(spectra: "LocatedSpectra", path: Path) -> None:
    from rbhyst.solve.located import SPECTRA_COLUMNS  # (the spectra's kernels only where there are spectra)

    labels, numbers = spectra.table()
    lines = [",".join(SPECTRA_COLUMNS)]
    lines += [f"{loc},{direction}," + ",".join(f"{v:.10g}" for v in row)
              for (loc, direction), row in zip(labels, numbers)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
