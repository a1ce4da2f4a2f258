"""The motions of a sweep: listed, found in folders by pattern, or the deck's own; their peak
ground acceleration and their scaling. A motion is ``excitation.support`` as deck data, with
every file path absolute."""

from __future__ import annotations

import copy
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rbhyst.model.deck import ACCEL_UNITS, Deck
from rbhyst.errors import InputError
from rbhyst.analyses.sweep.spec import MotionFolder, SweepSpec

#: the name of the deck's own support motion when the sweep lists none
DECK_MOTION = "deck"

#: every signal a deck may give (x3, p3, m1 and m2 in space), whose files a case's key names by content
SIGNAL_KEYS = (("support", "x1"), ("support", "x2"), ("force", "p1"), ("force", "p2"), ("force", "m3"),
               ("support", "x3"), ("force", "p3"), ("force", "m1"), ("force", "m2"))
#: the support's components
AXES = ("x1", "x2", "x3")


@dataclass(frozen=True)
class SweepMotion:
    name: str
    support: dict | None  # excitation.support as deck data; None: the deck's own (or none)
    where: str  # the sweep file's key that gives it, for messages


def sweep_motions(spec: SweepSpec, sweep_dir: Path) -> list[SweepMotion]:
    """The motions of the sweep in order: [[motions]], then each [[motion_folders]] sorted by name;
    none (an empty list) when it lists none."""
    out: list[SweepMotion] = []
    for i, m in enumerate(spec.motions or [], start=1):
        data = m.model_dump(mode="python", exclude_unset=True, exclude={"name"})
        out.append(SweepMotion(m.name, absolute_files(data, sweep_dir), f"motions[{i}]"))
    for i, f in enumerate(spec.motion_folders or [], start=1):
        out.extend(folder_motions(f, sweep_dir, f"motion_folders[{i}]"))
    problems = []
    first: dict[str, str] = {}
    for m in out:
        if m.name in first:
            problems.append(f"{m.where}: the motion name {m.name!r} is taken by {first[m.name]}")
        first.setdefault(m.name, m.where)
    if problems:
        raise InputError(problems)
    return out


def absolute_files(support: dict, base: Path) -> dict:
    """A copy of signals' data with each record ``file`` (and a random signal's PSD file) made
    absolute against ``base``."""
    out = copy.deepcopy(support)
    for comp in out.values():
        for key in ("file", "psd"):
            if isinstance(comp, dict) and isinstance(comp.get(key), str):
                p = Path(comp[key])
                comp[key] = str(p if p.is_absolute() else (base / p).resolve())
    return out


def folder_motions(f: MotionFolder, sweep_dir: Path, where: str) -> list[SweepMotion]:
    """The records of one [[motion_folders]] entry, paired by the text the '*' stands for."""
    folder = Path(f.folder)
    folder = folder if folder.is_absolute() else sweep_dir / folder
    if not folder.is_dir():
        raise InputError(f"{where}.folder: {folder}: no such folder")
    names = sorted(p.name for p in folder.iterdir() if p.is_file())
    found = {c: {stem: n for n in names if (stem := _match(pattern, n)) is not None}
             for c, pattern in ((c, getattr(f, c)) for c in AXES) if pattern is not None}
    problems = []
    comps = list(found)
    for c in comps:
        for other in comps:
            if other == c:
                continue
            pattern = getattr(f, other)
            for stem, n in found[c].items():
                if stem not in found[other]:
                    problems.append(f"{where}: {n} matches {c} = {getattr(f, c)!r} but {pattern.replace('*', stem)} "
                                    f"({other}) is not in {folder}")
    if problems:
        raise InputError(sorted(set(problems)))
    stems = sorted(found[comps[0]])
    if not stems:
        pats = " and ".join(f"{c} = {getattr(f, c)!r}" for c in comps)
        raise InputError(f"{where}: no file in {folder} matches {pats}")
    out = []
    for stem in stems:
        support = {}
        for c in comps:
            sig = {"file": str((folder / found[c][stem]).resolve()), "units": f.units, "scale": f.scale}
            if f.dt is not None:
                sig["dt"] = f.dt
            support[c] = sig
        out.append(SweepMotion(stem, support, f"{where} ({found[comps[0]][stem]})"))
    return out


def _match(pattern: str, name: str) -> str | None:
    head, tail = pattern.split("*")
    if len(name) > len(head) + len(tail) and name.startswith(head) and name.endswith(tail):
        return name[len(head):len(name) - len(tail)]
    return None


def deck_support(deck: Deck) -> dict | None:
    """The deck's own support motion as data with absolute paths (None: it has none)."""
    if deck.excitation is None or deck.excitation.support is None:
        return None
    data = deck.excitation.support.model_dump(mode="python", exclude_unset=True)
    data = {k: v for k, v in data.items() if v is not None}
    return absolute_files(data, deck.base) if data else None


def scaled(support: dict, factor: float) -> dict:
    """A copy with every component multiplied by ``factor``: a record's ``scale``, a sine's
    ``amplitude``."""
    out = copy.deepcopy(support)
    for comp in out.values():
        if not isinstance(comp, dict):
            continue
        if comp.get("type") == "sine":
            comp["amplitude"] = comp["amplitude"] * factor
        else:
            comp["scale"] = comp.get("scale", 1.0) * factor
    return out


def peak_acceleration(support: dict) -> float:
    """The larger of the components' peak |acceleration| in m/s2: over a record's samples (a
    line between samples peaks at one; random vibration's made as a run makes them), a sine's
    amplitude. Unreadable records raise InputError."""
    from rbhyst.files.units import check_declared
    from rbhyst.model.records import read_record

    peak = 0.0
    for c in AXES:
        comp = support.get(c)
        if comp is None:
            continue
        if comp.get("type") == "random":  # made into its samples, as a run makes it
            from rbhyst.model.deck import Random
            from rbhyst.model.system import random_series

            series = random_series(Random.model_validate(comp), Path.cwd())
            peak = max(peak, float(np.max(np.abs(series.values))))
            continue
        factor = ACCEL_UNITS[comp["units"]]
        if comp.get("type") == "sine":
            peak = max(peak, abs(comp["amplitude"]) * factor)
            continue
        record = read_record(Path(comp["file"]), comp.get("dt"))
        check_declared(record.declared, comp["units"])
        values = record.series.values
        peak = max(peak, float(np.max(np.abs(values))) * factor * abs(comp.get("scale", 1.0)))
    return peak


class FileDigests:
    """sha256 of each file's bytes, each file read once."""

    def __init__(self):
        self._known: dict[str, str] = {}

    def __call__(self, path: str) -> str:
        if path not in self._known:
            h = hashlib.sha256()
            try:
                with open(path, "rb") as fh:
                    for block in iter(lambda: fh.read(1 << 20), b""):
                        h.update(block)
            except FileNotFoundError:
                raise InputError(f"{path}: no such file") from None
            except OSError as exc:
                raise InputError(f"{path}: cannot be read ({exc.__class__.__name__})") from None
            self._known[path] = h.hexdigest()
        return self._known[path]
