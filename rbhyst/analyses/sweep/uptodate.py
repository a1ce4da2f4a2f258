"""Whether a finished sweep's files still stand: a run that computes nothing writes them again
only where one is missing, is older than the store, or was made from other inputs.

sweep.json keeps what its files were made from (``outputs_sha256``: the sha256 of cases.csv's
header and rows, every case's journal checksum, the axes, the units of the varied keys, the
fragility's limit states, which files were asked for and the rbhyst version) and the files
written then (``files``). A sweep whose cases are all in the store compares the two with its
own; a subset of a larger finished sweep (a motion left out) has other rows, so other inputs.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from rbhyst._version import __version__
from rbhyst.analyses.sweep.store import kept_sum

#: sweep.json's keys for what its files were made from and which files they are
OUTPUTS_SUM, OUTPUT_FILES = "outputs_sha256", "files"


def outputs_sum(outcome, table: tuple[list[str], list[list]], units: dict, histories: bool, plots: bool) -> str:
    """The sha256 of everything a sweep's files are made from (the module docstring)."""
    sweep = outcome.sweep
    sums = [kept_sum(outcome.results[c.key]) if c.key in outcome.results else None for c in sweep.cases]
    fragility = sweep.fragility.about() if sweep.fragility is not None else None
    body = [__version__, table[0], table[1], sums, sweep.vary_keys, sweep.scale_kind, sweep.levels, units,
            fragility, histories, plots]
    return json_sum(body, long=(2, 3))


def json_sum(body: list, long: tuple[int, ...] = ()) -> str:
    """The sha256 of json.dumps(body, sort_keys=True, separators=(",", ":"), default=repr), the
    items of ``body`` at ``long`` (lists: a sweep's rows) encoded one element at a time: the
    same text, never held whole (at 10^5 cases it was hundreds of megabytes)."""
    def dumps(x) -> bytes:
        return json.dumps(x, sort_keys=True, separators=(",", ":"), default=repr).encode()

    h = hashlib.sha256(b"[")
    for i, item in enumerate(body):
        if i:
            h.update(b",")
        if i in long:
            h.update(b"[")
            for j, x in enumerate(item):
                h.update(b"," + dumps(x) if j else dumps(x))
            h.update(b"]")
        else:
            h.update(dumps(item))
    h.update(b"]")
    return h.hexdigest()


def standing(out: Path, store: Path, made_from: str) -> bool:
    """True where ``out``/sweep.json says its files were made from ``made_from`` and every file
    it lists is there, a plain file, no older than ``store`` (the journal)."""
    try:
        about = json.loads((out / "sweep.json").read_text(encoding="utf-8"))
        since = store.stat().st_mtime_ns
    except (OSError, ValueError):
        return False
    files = about.get(OUTPUT_FILES) if isinstance(about, dict) else None
    if about.get(OUTPUTS_SUM) != made_from or not isinstance(files, list) or "sweep.json" not in files:
        return False
    for name in files:
        path = out / str(name)
        try:
            if path.is_symlink() or not path.is_file() or path.stat().st_mtime_ns < since:
                return False
        except OSError:
            return False
    return True
