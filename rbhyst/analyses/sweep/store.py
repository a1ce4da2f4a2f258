"""Where a sweep keeps its finished cases as they come: a folder of its own inside the output
folder, ``.rbhyst-sweep/``, that rbhyst makes and marks, and touches nothing else.

- ``journal.jsonl``: a first line that marks the file as rbhyst's, then one JSON line per
  finished case (its key, status, message, peaks, ...), appended and flushed as each batch
  comes back, with Ctrl-C and SIGTERM held off while a line is written. Each line carries the
  sha256 of its own content (``sha256``): a case is known by its latest line that proves
  itself. A line that does not (cut short by a crash, or altered since it was written) is set
  aside when the journal is next opened: :attr:`Journal.damaged` names it and why, the next
  append rewrites the journal without it, and its case is computed again.
- ``histories/``: with --save-histories, one Parquet file per batch of finished cases,
  written beside and renamed into place before the journal names it; the journal line keeps
  the file's sha256, and a file that no longer matches counts as missing.

A ``.rbhyst-sweep`` that rbhyst did not make (no marked journal in it) is refused, and so
is one that is a file or a link. ``--fresh`` removes the journal and the files it names, and
the folders when that leaves them empty.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import math
import os
import re
import shutil
import sys
import uuid
from array import array
from collections.abc import Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import NamedTuple

from rbhyst._version import __version__
from rbhyst.errors import DiskFull, InputError, is_disk_full
from rbhyst.files.outdir import signals_held

FOLDER = ".rbhyst-sweep"
JOURNAL = "journal.jsonl"
HISTORIES = "histories"
_MARK_KEY, _FORMAT = "rbhyst_sweep_journal", 2
_FORMATS = (1, 2)  # format 1 had no checksums: its cases are computed again
SUM = "sha256"
_KEY_IN_TEXT = re.compile(rb'"key": *"([0-9a-f]{16,64})"')


#: the groups of a case's numbers (rbhyst.analyses.sweep.worker.run_case) kept as Numbers
GROUPS = ("peaks", "energy", "accuracy", "stroke")


class Numbers(Mapping):
    """One group of a finished case's numbers (its peaks, say), read-only, in an array of floats
    whose names it shares with every case of the same names: the sweep's process holds every
    finished case until its tables are written, and as a dict of floats a case took 7.6 kB
    (seed deck, 60 numbers). None is kept as nan (a case's numbers are finite or None: JSON
    has no nan)."""

    __slots__ = ("_index", "_values")

    def __init__(self, index: dict[str, int], values: array):
        self._index = index
        self._values = values

    def __getitem__(self, key: str) -> float | None:
        v = self._values[self._index[key]]
        return None if v != v else v

    def __iter__(self):
        return iter(self._index)

    def __len__(self) -> int:
        return len(self._index)

    def items(self) -> list[tuple[str, float | None]]:
        """(name, value) of every number, in their order (a list: Mapping's view asks for each
        value by its name)."""
        return [(k, None if v != v else v) for k, v in zip(self._index, self._values)]


def compact(entry: dict, names: dict[tuple, dict[str, int]]) -> dict:
    """``entry`` with each group of floats (or None) as Numbers, in place; ``names``: the name
    indexes met so far, shared (a group holding anything else stays as it is)."""
    for g in GROUPS:
        d = entry.get(g)
        if type(d) is not dict:
            continue
        values = list(d.values())
        kinds = set(map(type, values))
        if not kinds <= _FLOAT_OR_NONE:
            continue
        if _NONE in kinds:
            values = [math.nan if v is None else v for v in values]
        key = tuple(d)
        index = names.get(key)
        if index is None:
            index = names[key] = {k: i for i, k in enumerate(key)}
        entry[g] = Numbers(index, array("d", values))
    # each line's JSON (each batch's pickle) has its own copies of the keys' strings, some 50 bytes
    # each: one copy of each for every case (interned), and of the values that repeat
    items = list(entry.items())
    entry.clear()
    entry.update((sys.intern(k), v) for k, v in items)
    for k in _REPEATED:
        v = entry.get(k)
        if type(v) is str:
            entry[k] = sys.intern(v)
    return entry


_NONE = type(None)
_FLOAT_OR_NONE = {float, _NONE}
#: an entry's strings that most cases share
_REPEATED = ("status", "rbhyst_version", "message")


def _plain(value):
    """What JSON writes of Numbers: the dict it stands for."""
    if isinstance(value, Numbers):
        return dict(value.items())
    raise TypeError(f"Object of type {type(value).__name__} is not JSON serializable")


def kept_sum(entry: dict) -> str:
    """An entry's line_sum, as the journal wrote or read it (where it did: else worked out)."""
    known = entry.get(SUM)
    return known if known is not None else line_sum(entry)


def line_sum(entry: dict) -> str:
    """The sha256 of a journal entry's content: its canonical JSON without the sum itself."""
    body = {k: v for k, v in entry.items() if k != SUM}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":"),
                                     allow_nan=False, default=_plain).encode()).hexdigest()


def file_sum(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


class Damage(NamedTuple):
    """A journal line that does not prove its content: its case key (None where too little
    of the line is left to tell) and why, in words."""

    key: str | None
    why: str


class Journal:
    """The finished cases of an output folder, by key."""

    def __init__(self, out: Path, fresh: bool = False):
        self.out = Path(out)
        self.folder = self.out / FOLDER
        self.path = self.folder / JOURNAL
        self._names: dict[tuple, dict[str, int]] = {}  # the cases' groups' names, shared (compact)
        self._check_ours()
        if fresh:
            self.clear()
        self.damaged: list[Damage] = []
        self._ragged = False
        self._free: int | None = None
        self._sums: dict[str, str] = {}  # history file name -> its sha256, once checked
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
        """The entries that prove their content, by key (the latest line wins); what does not
        goes into ``self.damaged``, except a case that a later good line stands for."""
        self.damaged = []
        if not self.path.exists():
            return {}
        entries: dict[str, dict] = {}
        bad: dict[str | None, str] = {}
        unknown: list[str] = []
        with open(self.path, "rb") as fh:  # (a line at a time: a journal of 10^5 cases is 240 MB)
            first = fh.readline()
            self._ragged = bool(first) and not first.endswith(b"\n")  # the next line must start on its own
            try:
                version = json.loads(first).get(_MARK_KEY)
            except (ValueError, AttributeError):
                version = None
            for i, line in enumerate(fh, start=1):
                # (only the file's last line can lack its newline: one cut short as it was written)
                self._ragged = not line.endswith(b"\n")
                self._take(line, i, self._ragged, version, entries, bad, unknown)
        self.damaged = [Damage(k, w) for k, w in bad.items()] + [Damage(None, w) for w in unknown]
        return entries

    def _take(self, line: bytes, i: int, last: bool, version, entries: dict, bad: dict, unknown: list) -> None:
        """Line ``i`` of the journal into ``entries``, or why not into ``bad`` (by its case's key)
        or ``unknown``; ``last``: the file's last line, without its newline."""
        if not line.strip():
            return
        why = None
        try:
            e = json.loads(line)
        except ValueError:
            e = None
        if not (isinstance(e, dict) and isinstance(e.get("key"), str)):
            why = ("cut short by an interrupted write" if last
                   else f"line {i + 1} of {JOURNAL} is damaged: cut short or edited")
        elif version == 1 and SUM not in e:
            why = "kept by an earlier rbhyst without a checksum"
        elif e.get(SUM) != line_sum(e):
            why = f"line {i + 1} of {JOURNAL} was altered after it was written: its checksum differs"
        if why is None:
            entries[e["key"]] = compact(e, self._names)
            bad.pop(e["key"], None)
            return
        m = _KEY_IN_TEXT.search(line)
        key = e["key"] if isinstance(e, dict) and isinstance(e.get("key"), str) else (
            m.group(1).decode() if m else None)
        entries.pop(key, None)  # an older good line of the case does not stand for it either
        if key is None:
            unknown.append(why)
        else:
            bad[key] = why

    def open(self) -> None:
        """Create the folder and the marked journal if needed; then append."""
        if self._fh is not None:
            return
        with signals_held(), self.space():
            self.folder.mkdir(parents=True, exist_ok=True)
            self._free = shutil.disk_usage(self.folder).free
            new = not self.path.exists()
            self._fh = self._locked(open(self.path, "ab"))
            for p in (self.folder / HISTORIES).glob(".*.parquet.partial"):
                p.unlink()  # left by a sweep that was killed while writing them
            if new:
                self._fh.write(_mark_line())
                self._fh.flush()
            elif self.damaged or self._ragged or not _marked(self.path, (_FORMAT,)):
                self._rewrite()

    @contextmanager
    def space(self, partial: Path | None = None):
        """A full disk while keeping cases becomes one DiskFull line saying what is kept (a
        line it cut short is set aside by its checksum next time); ``partial``, a file being
        written, is removed."""
        try:
            yield
        except OSError as exc:
            if not is_disk_full(exc):
                raise
            if partial is not None:
                partial.unlink(missing_ok=True)
            fh, self._fh = self._fh, None
            if fh is not None:
                try:
                    fh.close()
                except OSError:  # its buffer cannot be written either
                    pass
            n = len(self.entries)
            kept = (f"{n} finished case{'s are' if n != 1 else ' is'} kept: the same command computes the rest"
                    if n else "no case was kept")
            raise DiskFull(self.folder, self._free, "the finished cases", kept) from None

    def _locked(self, fh):
        try:  # one sweep at a time writes here
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.close()
            self._fh = None
            raise InputError(f"{self.out}: another rbhyst sweep is writing into this folder") from None
        return fh

    def _rewrite(self) -> None:
        """The journal anew, with the lines that prove themselves only (under the lock): written
        beside, flushed to disk and renamed over the old one, so that a crash leaves one or the
        other whole."""
        tmp = self.folder / f".{JOURNAL}.partial"
        with self.space(tmp), open(tmp, "wb") as fh:
            fh.write(_mark_line())
            fh.write(b"".join(_entry_line(e) for e in self.entries.values()))
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, self.path)
        old, self._fh = self._fh, None
        old.close()  # its lock goes with it; the new file is locked at once
        self._fh = self._locked(open(self.path, "ab"))

    def add(self, entries: list[dict]) -> None:
        """Append finished cases, whole lines only, and flush them to the file."""
        self.open()
        for e in entries:
            e.pop(SUM, None)  # (a case computed again: its sum is its new content's)
        text = b"".join(_entry_line(e) for e in entries)
        with signals_held(), self.space():
            self._fh.write(text)
            self._fh.flush()
        for e in entries:  # (kept compact, with the sum its line carries: the caller's dicts too, in place)
            self.entries[e["key"]] = compact(e, self._names)

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

    def history_problem(self, key: str) -> str | None:
        """None where the case's histories are on disk as they were written; else why not."""
        e = self.entries.get(key)
        if not (e and e.get("history")):
            return "not kept"
        name = e["history"]
        path = self.history_path(name)
        if not path.is_file():
            return f"its histories file {HISTORIES}/{name} is missing"
        if name not in self._sums:
            self._sums[name] = file_sum(path)
        if e.get("history_sha256") != self._sums[name]:
            return f"its histories file {HISTORIES}/{name} was altered after it was written"
        return None

    def has_history(self, key: str) -> bool:
        return self.history_problem(key) is None

    def sum_of_history(self, name: str) -> str:
        """The sha256 of a history file just written (kept in its cases' journal lines)."""
        self._sums[name] = file_sum(self.history_path(name))
        return self._sums[name]

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


def _mark_line() -> bytes:
    mark = {_MARK_KEY: _FORMAT, "about": "Finished cases of rbhyst sweep, one per line, by key; each line "
            f"carries the sha256 of its canonical JSON without '{SUM}'.", "rbhyst_version": __version__}
    return (json.dumps(mark) + "\n").encode()


def _entry_line(entry: dict) -> bytes:
    """The journal's line of an entry, its sum in it; the entry keeps the sum too (kept_sum)."""
    entry[SUM] = line_sum(entry)
    return (json.dumps(entry, allow_nan=False, default=_plain) + "\n").encode()


def _marked(path: Path, formats=_FORMATS) -> bool:
    try:
        with open(path, "rb") as fh:
            first = json.loads(fh.readline())
        return isinstance(first, dict) and first.get(_MARK_KEY) in formats
    except (OSError, ValueError):
        return False
