"""A sweep's cases: the product motions x scale x vary (or the listed cases), each a set of
deck values checked like a deck before anything runs, and each with a key that says what
its result depends on.

The key is a sha256 of: the case's whole validated deck (defaults filled in; its title,
output.directory and output.plots left out: they change no number), with every record file
replaced by the sha256 of its bytes, and the rbhyst version. A case whose key a results
folder already holds is not run again; change the base deck, a record's contents, a value,
or rbhyst, and the key changes. A file moved or renamed with the same contents keeps it.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rbhyst._version import __version__
from rbhyst.model.deck import ACCEL_UNITS, Deck, load_deck, parse_deck
from rbhyst.errors import InputError
from rbhyst.analyses.sweep.motions import (DECK_MOTION, SIGNAL_KEYS, FileDigests, SweepMotion, absolute_files,
                                           deck_support, peak_acceleration, scaled, sweep_motions)
from rbhyst.analyses.sweep.spec import Cluster, SweepSpec, read_spec


@dataclass(frozen=True)
class Case:
    """One run of the sweep."""

    number: int  # 1-based, in the sweep's order (motions outermost, then scale, then vary)
    motion: str
    scale: float  # the level as the sweep gives it: a factor, or a target PGA in g
    factor: float | None  # what the motion is multiplied by (None: its records could not be read)
    vary: dict[str, Any]  # the case's vary (or cases) values by key as written; absent: the deck's
    values: dict[str, Any]  # what the case changes in the base deck (Deck.with_values)
    key: str
    problem: str | None = None  # why the case fails before it runs (a record that cannot be read)


@dataclass(frozen=True)
class BaseDeck:
    """What a worker needs to rebuild every case's deck: the base deck's data (record paths
    absolute) and the file it came from."""

    data: dict
    source: str | None
    token: str  # sha256 of the data: a worker parses each base deck once

    def deck(self) -> Deck:
        d = parse_deck(self.data)
        d._source = Path(self.source) if self.source else None
        return d


@dataclass
class Sweep:
    path: Path
    spec: SweepSpec
    deck_path: Path
    base: BaseDeck
    scale_kind: str  # "factors" or "pga_g"
    levels: list[float]
    motions: list[str]
    vary_keys: list[str]
    cases: list[Case] = field(default_factory=list)
    fragility: Any = None  # analyses.fragility.FragilityPlan, with [[limit_states]]
    cluster: Cluster | None = None  # the sweep file's [cluster], its files' paths absolute

    @property
    def stem(self) -> str:
        return self.path.stem

    def default_out(self) -> Path:
        return self.path.parent / "results" / self.path.stem

    def short_deck(self) -> Deck:
        """The first case cut to ten steps: enough to compile or load the kernels."""
        deck = self.base.deck().with_values(self.cases[0].values)
        return deck.with_values({"analysis.duration": 10 * deck.analysis.dt})


def load_sweep(path: str | Path) -> Sweep:
    """Read a sweep file, its base deck and its motions, and build and check every case
    (InputError, one line per problem, before anything runs)."""
    path = Path(path)
    spec = read_spec(path)
    here = path.resolve().parent
    deck_path = Path(spec.deck)
    deck_path = deck_path if deck_path.is_absolute() else here / deck_path
    try:
        deck = load_deck(deck_path)
    except InputError as err:
        raise InputError([p if p.startswith(str(deck_path)) else f"deck {spec.deck}: {p}" for p in err.problems]) \
            from None
    base = _base_deck(deck)
    deck = base.deck()
    if deck.body is None or deck.body.dimensions == 2:
        vertical = [f"motions[{i}].x3" for i, m in enumerate(spec.motions or [], start=1) if m.x3 is not None]
        vertical += [f"motion_folders[{i}].x3" for i, f in enumerate(spec.motion_folders or [], start=1)
                     if f.x3 is not None]
        if vertical:
            raise InputError([f"{key}: the deck {spec.deck} is in the plane (2-D): support motion along x1 and x2 "
                              "only (x3 is for a deck in space)" for key in vertical])
    motions = sweep_motions(spec, here)
    own = not motions
    if own:
        motions = [SweepMotion(DECK_MOTION, deck_support(deck), "deck")]
    kind = spec.scale.kind if spec.scale is not None else "factors"
    levels = spec.scale.levels if spec.scale is not None else [1.0]
    if spec.scale is not None and motions[0].support is None:
        raise InputError(f"scale: the deck {spec.deck} has no support motion to scale; give [[motions]]")
    digests = FileDigests()
    problems = []
    for m in motions:  # every file named must exist before anything runs
        for c in ("x1", "x2", "x3"):
            comp = (m.support or {}).get(c)
            for key in ("file", "psd"):  # a record, a random signal's PSD file
                if comp and isinstance(comp.get(key), str):
                    try:
                        digests(comp[key])
                    except InputError as err:
                        problems.append(f"{m.where}.{c}.{key}: {err.problems[0]}")
    if problems:
        raise InputError(problems)
    combos, vary_keys = _combinations(spec, [m.name for m in motions], levels)
    sweep = Sweep(path=path, spec=spec, deck_path=deck_path, base=base, scale_kind=kind, levels=levels,
                  motions=[m.name for m in motions], vary_keys=vary_keys,
                  cluster=spec.cluster.resolved(here) if spec.cluster is not None else None)
    sweep.cases = _cases(deck, motions, combos, kind, own, digests)
    if spec.limit_states:
        from rbhyst.analyses.fragility import plan_fragility

        sweep.fragility = plan_fragility(sweep)
    return sweep


def _base_deck(deck: Deck) -> BaseDeck:
    data = deck.model_dump(mode="python", exclude_unset=True)
    ex = data.get("excitation")
    for group in ("support", "force"):
        if ex and ex.get(group):
            ex[group] = absolute_files(ex[group], deck.base)
    token = hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()
    return BaseDeck(data, str(deck.source) if deck.source else None, token)


def _combinations(spec: SweepSpec, motions: list[str], levels: list[float]):
    """(motion, level, vary values) in the sweep's order, and the vary keys as written."""
    if spec.cases is None:
        vary = spec.vary or {}
        keys = list(vary)
        combos = [(m, s, dict(zip(keys, values)))
                  for m in motions for s in levels for values in itertools.product(*vary.values())]
        return combos, keys
    problems = []
    for i, c in enumerate(spec.cases, start=1):
        if c.motion is not None and c.motion not in motions:
            problems.append(f"cases[{i}].motion: no motion {c.motion!r}; the motions are {', '.join(motions)}")
    if problems:
        raise InputError(problems)
    keys = list(dict.fromkeys(k for c in spec.cases for k in c.values))
    extra = [c.scale for c in spec.cases if c.scale is not None and c.scale not in levels]
    all_levels = list(dict.fromkeys([*levels, *extra]))
    combos = []
    for m in motions:
        for s in all_levels:
            for c in spec.cases:
                if (c.motion is None or c.motion == m) and (s == c.scale if c.scale is not None else s in levels):
                    combos.append((m, s, dict(c.values)))
    return combos, keys


def _cases(deck: Deck, motions: list[SweepMotion], combos, kind: str, own: bool, digests: FileDigests) -> list[Case]:
    from rbhyst.model.settings import settings_from_deck

    by_name = {m.name: m for m in motions}
    pga: dict[str, float | str] = {}  # m/s2, or why it cannot be known
    if kind == "pga_g":
        for m in motions:
            try:
                p = peak_acceleration(m.support)
                pga[m.name] = p if p > 0 else "its peak acceleration is 0: no factor scales it to a target"
            except InputError as err:
                pga[m.name] = "; ".join(err.problems)
    cases: list[Case] = []
    failures: dict[str, list[str]] = {}
    for number, (name, level, vary) in enumerate(combos, start=1):
        m = by_name[name]
        problem = None
        if kind == "pga_g":
            p = pga[name]
            factor = level * ACCEL_UNITS["g"] / p if isinstance(p, float) else None
            problem = p if isinstance(p, str) else None
        else:
            factor = level
        values: dict[str, Any] = {}
        if m.support is not None and factor is not None and not (own and factor == 1.0):
            support = scaled(m.support, factor)
            if deck.excitation is None:
                values["excitation"] = {"support": support}
            else:
                values["excitation.support"] = support
        values.update(vary)
        label = _label(number, name, level, vary)
        try:
            d = deck.with_values(values)
            settings_from_deck(d)
            key = case_key(d, digests)
        except InputError as err:
            for p in err.problems:
                failures.setdefault(p, []).append(label)
            continue
        cases.append(Case(number, name, level, factor, vary, values, key, problem))
    if failures:
        n = len(combos)
        lines = []
        for p, labels in failures.items():
            more = " (every case)" if len(labels) == n and n > 1 else \
                (f" (and {len(labels) - 1} more case{'s' * (len(labels) > 2)})" if len(labels) > 1 else "")
            lines.append(f"{labels[0]}: {p}{more}")
        raise InputError(lines)
    return cases


def _label(number: int, motion: str, level: float, vary: dict) -> str:
    parts = [f"motion {motion}", f"scale {level:g}"] + [f"{k} = {format_value(v)}" for k, v in vary.items()]
    return f"case {number} ({', '.join(parts)})"


def format_value(v) -> str:
    """A vary value as cases.csv and messages show it: numbers exactly (repr), text as it is,
    booleans as TOML writes them, anything else as JSON."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float, str)):
        return repr(v) if isinstance(v, float) else str(v)
    return json.dumps(v, sort_keys=True, default=str)


def case_key(deck: Deck, digests: FileDigests) -> str:
    """sha256 (hex, first 32 digits) of what the case's result depends on (see the module)."""
    data = deck.model_dump(mode="json")
    data.pop("title", None)
    data.pop("qualify", None)  # what `rbhyst qualify` holds the deck to: no number of a run
    data["output"] = {"every": data["output"]["every"]}
    ex = data.get("excitation") or {}
    for group, comp in SIGNAL_KEYS:
        sig = (ex.get(group) or {}).get(comp)
        for key in ("file", "psd"):  # a record's file, a random signal's PSD file
            if isinstance(sig, dict) and isinstance(sig.get(key), str):
                p = Path(sig[key])
                sig[key] = "sha256:" + digests(str(p if p.is_absolute() else deck.base / p))
    text = json.dumps({"deck": data, "rbhyst_version": __version__}, sort_keys=True, allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:32]
