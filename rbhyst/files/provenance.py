"""What a signed report must say it was made from: when, by which rbhyst, by which command, and
the sha256 of every file read (the deck, its records, RRS files), so that a reader can check
that the files in hand are those the numbers come from."""

from __future__ import annotations

import hashlib
from datetime import UTC, datetime
from pathlib import Path

from rbhyst._version import __version__
from rbhyst.errors import InputError

#: bytes read at a time: a record of any size is hashed in constant memory
CHUNK = 1 << 20


def sha256_of(path: Path) -> str:
    """The file's sha256, hex (what ``sha256sum`` prints); a file that cannot be read is an
    InputError naming it."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(CHUNK), b""):
                digest.update(block)
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.__class__.__name__})") from None
    return digest.hexdigest()


def input_entry(key: str, path: Path, given: str) -> dict:
    """One file read: the deck key (or option) that named it, the name as given there, its
    size and sha256."""
    path = Path(path)
    return {"key": key, "file": given, "bytes": path.stat().st_size, "sha256": sha256_of(path)}


def provenance(command: str | None, inputs: list[tuple[str, Path, str]], now: datetime | None = None) -> dict:
    """summary.json's and qualification.json's ``provenance``: the time the work started (UTC,
    to the second), rbhyst's version, the command as run (None: through the Python API) and
    each input (``inputs``: (key, path, as given), each file once, first key kept)."""
    seen: set[Path] = set()
    entries = []
    for key, path, given in inputs:
        real = Path(path).resolve()
        if real not in seen:
            seen.add(real)
            entries.append(input_entry(key, real, given))
    when = (now or datetime.now(UTC)).astimezone(UTC)
    return {"started_utc": when.isoformat(timespec="seconds").replace("+00:00", "Z"),
            "rbhyst_version": __version__, "command": command, "inputs": entries}
