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
    from rbhyst.model.deck import Deck
    from rbhyst.solve.located import LocatedSpectra


class CsvWriter:
    """time_history.csv, written chunk by chunk: 10 significant digits, one header row.

    ``CsvWriter(path)`` is what a run is given; the run calls it with its columns to start the
    file (a run that is repeated, as tolerance mode's ladder does, starts it over), then
    ``add(rows)`` for every chunk and ``close()``. A chunk is cut into pieces of PIECE_VALUES
    values, which two threads of its own (two lanes of work arrays and text buffers) format
    in turn while the caller goes on with the next chunk, the error estimate and the figures,
    each piece written after the one before: the compiled formatting and the write (most of it
    the system finding fresh pages for the file) hold no lock of Python's. Formatting (33 ns a
    value) is slower than the loop that makes the rows: one thread held a long run's loop back
    (10^6 steps, 540 MB: 3.0-3.2 -> 2.2 s in the process), and a run's chunks are of any size
    (the seed deck's 40,001 rows came as 33,333 and 6,668: formatted whole, the large one kept
    one thread busy while the other core idled, its rows written 60-90 ms after the loop, in
    pieces 20-40 ms). At most IN_FLIGHT chunks wait their turn (a run faster than its disk waits
    for it: memory stays bounded); a chunk must not change once added (a run's tables are new
    for every chunk). ``close()`` leaves the file to close after its last write; ``wait()``
    returns once it has, and raises what a write raised. Whoever gave the run a CsvWriter waits
    for it before the folder is put in place or removed.
    """

    #: chunks handed to the threads and not yet written
    IN_FLIGHT = 2
    #: values formatted in one lane's turn (a few MB of text, the lane's buffer kept from turn to turn)
    PIECE_VALUES = 131_072

    def __init__(self, path: Path):
        self.path = Path(path)
        self._fh = None
        self._last: threading.Thread | None = None  # the last chunk's (it ends after every earlier one)
        self._waiting: collections.deque[threading.Thread] = collections.deque()
        self._error: BaseException | None = None

    def __call__(self, columns: tuple[str, ...]) -> "CsvWriter":
        from rbhyst.results.csvtext import RowsText

        self.wait()
        self._texts = (RowsText(), RowsText())  # two lanes: a chunk's piece k is formatted in lane k % 2
        self._lanes: list[threading.Thread | None] = [None, None]  # each lane's thread, the last chunk's
        self._written: threading.Event | None = None  # set once the last chunk's last piece is written
        self._fh = open(self.path, "wb")
        self._fh.write((",".join(columns) + "\n").encode())
        return self

    def add(self, rows: np.ndarray) -> None:
        while len(self._waiting) >= self.IN_FLIGHT:
            self._join(self._waiting.popleft())
        self._join(None)  # (a write that failed: said now)
        step = max(1, self.PIECE_VALUES // max(1, rows.shape[1]))
        pieces = [rows[first:first + step] for first in range(0, max(len(rows), 1), step)]
        written = [threading.Event() for _ in pieces]
        fh, before = self._fh, self._written

        def lane(text, lane_before, ks):
            # piece k: formatted once this lane's text before is written (its buffer is free),
            # beside the other lane's; written after piece k - 1
            try:
                if lane_before is not None:
                    lane_before.join()
                for k in ks:
                    out = None
                    try:
                        if self._error is None:
                            out = text(pieces[k])
                    except BaseException as exc:  # (raised in the caller's thread by wait() or the next add())
                        self._error = self._error or exc
                    prior = written[k - 1] if k else before
                    if prior is not None:
                        prior.wait()
                    if out is not None and self._error is None:
                        try:
                            fh.write(out)
                        except BaseException as exc:
                            self._error = self._error or exc
                    written[k].set()
            finally:
                for k in ks:  # (never a piece after it waiting for ever)
                    written[k].set()

        for j in range(min(2, len(pieces))):
            ks = range(j, len(pieces), 2)
            thread = threading.Thread(target=lane, args=(self._texts[j], self._lanes[j], ks),
                                      name=f"{self.path.name} writer", daemon=True)
            thread.start()
            self._lanes[j] = thread
            if len(pieces) - 1 in ks:
                self._last = thread  # (it writes the chunk's last piece, after every other)
        self._written = written[-1]
        self._waiting.append(self._last)

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


def deck_as_run(deck: Deck, **overrides) -> dict:
    """The deck's keys as given, with the run's overrides (integrator, dt, tolerance,
    estimate_error) in [analysis]: what summary.json keeps of the deck, so that a report can
    show what ran."""
    data = deck.model_dump(mode="json", exclude_unset=True)
    given = {k: v for k, v in overrides.items() if v is not None}
    if given:
        data.setdefault("analysis", {}).update(given)
    return data


def write_summary(result: Result, path: Path) -> None:
    Path(path).write_text(json.dumps(result.summary(), indent=2) + "\n")


def spectra_file(spectra) -> str:
    """The file a run's spectra go to: spectra.csv, or srs.csv for shock response spectra."""
    return "srs.csv" if spectra.kind == "srs" else "spectra.csv"


def write_spectra_csv(spectra: "LocatedSpectra", path: Path) -> None:
    """spectra.csv (rbhyst.solve.located.SPECTRA_COLUMNS), or a run's srs.csv (LocatedShockSpectra:
    rbhyst.solve.located_shock.RUN_SRS_COLUMNS)."""
    if spectra.kind == "srs":
        from rbhyst.solve.located_shock import RUN_SRS_COLUMNS as columns
    else:
        from rbhyst.solve.located import SPECTRA_COLUMNS as columns  # (the spectra's kernels only where there are spectra)

    labels, numbers = spectra.table()
    lines = [",".join(columns)]
    lines += [f"{loc},{direction}," + ",".join(f"{v:.10g}" for v in row)
              for (loc, direction), row in zip(labels, numbers)]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_srs_csv(srs, path: Path) -> None:
    """srs.csv: one row per Q and frequency (rbhyst.solve.shock_spectra.SRS_COLUMNS)."""
    from rbhyst.solve.shock_spectra import SRS_COLUMNS

    lines = [",".join(SRS_COLUMNS)] + [",".join(f"{v:.10g}" for v in row) for row in srs.table()]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
