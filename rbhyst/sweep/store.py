"""Where a sweep keeps its finished cases as they come: a folder of its own inside the output
folder, ``.rbhyst-sweep/``, that rbhyst makes and marks, and touches nothing else.

- ``journal.jsonl``: a first line that marks the file as rbhyst's, then one JSON line per
  finished case (its key, status, message, peaks, ...), appended and flushed as each batch
  comes back, with Ctrl-C and SIGTERM held off while a line is written. A line cut short (a
  power cut) is dropped when the journal is next opened; a case is known by its latest line.
- ``histories/``: with --save-histories, one Parquet file per batch of finished cases,
  written beside and renamed into place before the journal names it.

A ``.rbhyst-sweep`` that rbhyst did not make (no marked journal in it) is refused, and so
is one that is a file or a link. ``--fresh`` removes the journal and the files it names, and
the folders when that leaves them empty.
"""

from __future__ import annotations

import fcntl
import json
import os
import uuid
from pathlib import Path

from .. import __version__
from ..errors import InputError
from ..outdir import signals_held

FOLDER = ".rbhyst-sweep"
JOURNAL = "journal.jsonl"
HISTORIES = "histories"
_MARK_KEY, _FORMAT = "rbhyst_sweep_journal", 1


class Journal:
    """The finished cases of an output folder, by key."""

    def __init__(self, out: Path, fresh: bool = False):
        self.out = Path(out)
        self.folder = self.out / FOLDER
        self.path = self.folder / JOURNAL
        self._check_ours()
        if fresh:
            self.clear()
        self.entries: dict[str, dict] = self._read()
        self._fh = None

    # ---------------------------------------------------------------- ownership

    def _check_ours(self) -> None:
        f = self.folder
        if f.is_symlink() or (f.exists() and not f.is_dir()):
            raise InputError(f"{self.out}: {FOLDER} is in the way and rbhyst did not make it; move it away or "
                             "choose another output folder")
        if not f.exists():
            return
        if not (self.path.is_file() and not self.path.is_symlink() and _marked(self.path)):
            if not any(f.iterdir()):
                return  # an empty folder (made just before an interrupt): nothing to lose
            raise InputError(f"{self.out}: {FOLDER} exists and rbhyst did not make it (no {JOURNAL} of "
                             "rbhyst's in it); move it away or choose another output folder")

    # ---------------------------------------------------------------- reading and writing

    def _read(self) -> dict[str, dict]:
        if not self.path.exists():
            return {}
        entries: dict[str, dict] = {}
        with open(self.path, "rb") as fh:
            data = fh.read()
        lines = data.split(b"\n")
        for line in lines[1:]:
            try:
                e = json.loads(line)
            except ValueError:
                continue  # a line cut short by a crash
            if isinstance(e, dict) and isinstance(e.get("key"), str):
                entries[e["key"]] = e
        if data and not data.endswith(b"\n"):  # cut short: the next line must start on a line of its own
            with signals_held(), open(self.path, "r+b") as fh:
                fh.truncate(data.rfind(b"\n") + 1)
        return entries

    def open(self) -> None:
        """Create the folder and the marked journal if needed; then append."""
        if self._fh is not None:
            return
        with signals_held():
            self.folder.mkdir(parents=True, exist_ok=True)
            new = not self.path.exists()
            self._fh = open(self.path, "ab")
            try:  # one sweep at a time writes here
                fcntl.flock(self._fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                self._fh.close()
                self._fh = None
                raise InputError(f"{self.out}: another rbhyst sweep is writing into this folder") from None
            for p in (self.folder / HISTORIES).glob(".*.parquet.partial"):
                p.unlink()  # left by a sweep that was killed while writing them
            if new:
                mark = {_MARK_KEY: _FORMAT, "about": "Finished cases of rbhyst sweep, one per line, by key.",
                        "rbhyst_version": __version__}
                self._fh.write((json.dumps(mark) + "\n").encode())
                self._fh.flush()

    def add(self, entries: list[dict]) -> None:
        """Append finished cases, whole lines only, and flush them to the file."""
        self.open()
        text = b"".join((json.dumps(e, allow_nan=False) + "\n").encode() for e in entries)
        with signals_held():
            self._fh.write(text)
            self._fh.flush()
        for e in entries:
            self.entries[e["key"]] = e

    def close(self) -> None:
        if self._fh is not None:
            try:
                os.fsync(self._fh.fileno())
            finally:
                self._fh.close()
                self._fh = None

    # ---------------------------------------------------------------- histories

    def history_path(self, name: str) -> Path:
        return self.folder / HISTORIES / name

    def new_history_file(self) -> tuple[str, Path]:
        """A fresh name for a batch's histories, and a temporary path beside it to write first."""
        self.open()
        (self.folder / HISTORIES).mkdir(exist_ok=True)
        name = f"{uuid.uuid4().hex}.parquet"
        return name, self.folder / HISTORIES / f".{name}.partial"

    def has_history(self, key: str) -> bool:
        e = self.entries.get(key)
        return bool(e and e.get("history") and self.history_path(e["history"]).is_file())

    # ---------------------------------------------------------------- starting over

    def clear(self) -> None:
        """Remove the journal and the history files it names; the folders if that empties them."""
        if not self.path.exists():
            return
        names = {e.get("history") for e in self._read().values()} - {None}
        with signals_held():
            for n in names:
                p = self.history_path(str(n))
                if p.parent == self.folder / HISTORIES and p.is_file():
                    p.unlink()
            for p in (self.folder / HISTORIES).glob(".*.parquet.partial"):
                p.unlink()
            self.path.unlink()
            for d in (self.folder / HISTORIES, self.folder):
                try:
                    d.rmdir()
                except OSError:
                    pass


def _marked(path: Path) -> bool:
    try:
        with open(path, "rb") as fh:
            first = json.loads(fh.readline())
        return isinstance(first, dict) and first.get(_MARK_KEY) == _FORMAT
    except (OSError, ValueError):
        return False
