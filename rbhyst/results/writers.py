"""The files of a run: time_history.csv streamed chunk by chunk (a run of any length needs
one chunk of rows in memory), summary.json, spectra.csv."""

from __future__ import annotations

import collections
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
    ``add(rows)`` for every chunk and ``close()``. A chunk is formatted and written by a thread
    of its own while the caller goes on with the next chunk, the error estimate and the
    figures: the compiled formatting and the write (most of it the system finding fresh pages
    for the file) hold no lock of Python's. Two chunks are formatted at once, in two lanes of
    work arrays and text buffers, and written in turn: formatting (33 ns a value) is slower
    than the loop that makes the rows, and one thread held a long run's loop back (10^6 steps,
    540 MB: 3.0-3.2 -> 2.2 s in the process). At most IN_FLIGHT chunks wait their turn (a run
    faster than its disk waits for it: memory stays bounded); a chunk must not change once
    added (a run's tables are new for every chunk). ``close()`` leaves the file to close after
    its last write; ``wait()`` returns once it has, and raises what a write raised. Whoever
    gave the run a CsvWriter waits for it before the folder is put in place or removed.
    """

    #: chunks handed to the threads and not yet written
    IN_FLIGHT = 2

    def __init__(self, path: Path):
        self.path = Path(path)
        self._fh = None
        self._last: threading.Thread | None = None  # the last chunk's (it ends after every earlier one)
        self._waiting: collections.deque[threading.Thread] = collections.deque()
        self._error: BaseException | None = None

    def __call__(self, columns: tuple[str, ...]) -> "CsvWriter":
        from rbhyst.results.csvtext import RowsText

        self.wait()
        self._texts = (RowsText(), RowsText())  # two lanes: chunk k is formatted in lane k % 2
        self._lane_last: list[threading.Thread | None] = [None, None]
        self._chunks = 0
        self._fh = open(self.path, "wb")
        self._fh.write((",".join(columns) + "\n").encode())
        return self

    def add(self, rows: np.ndarray) -> None:
        while len(self._waiting) >= self.IN_FLIGHT:
            self._join(self._waiting.popleft())
        self._join(None)  # (a write that failed: said now)
        lane = self._chunks % 2
        self._chunks += 1
        fh, text, lane_before, before = self._fh, self._texts[lane], self._lane_last[lane], self._last

        def step():
            # formatted beside the chunk before (the other lane), once this lane's last text is
            # written; written after the chunk before
            out = None
            try:
                if lane_before is not None:
                    lane_before.join()
                if self._error is None:
                    out = text(rows)
            except BaseException as exc:  # (raised in the caller's thread by wait() or the next add())
                self._error = self._error or exc
            if before is not None:
                before.join()
            if out is not None and self._error is None:
                try:
                    fh.write(out)
                except BaseException as exc:
                    self._error = self._error or exc

        thread = threading.Thread(target=step, name=f"{self.path.name} writer", daemon=True)
        thread.start()
        self._last = self._lane_last[lane] = thread
        self._waiting.append(thread)

    def close(self) -> None:
        """The file closes after its last write, whether or not a write failed; wait() for it."""
        if self._fh is None:
            return
        fh, before = self._fh, self._last
        self._fh = None
        self._texts = None  # (their buffers freed once the last chunk is written, for the next arrays)

        def step():
            if before is not None:
                before.join()
            try:
                fh.close()
            except BaseException as exc:  # (raised in the caller's thread by wait())
                self._error = self._error or exc

        self._last = threading.Thread(target=step, name=f"{self.path.name} closer", daemon=True)
        self._last.start()

    def wait(self) -> None:
        """Return once every chunk added so far is written; raise what a write raised."""
        self._waiting.clear()
        self._join(self._last)

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
