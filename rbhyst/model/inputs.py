"""The files a deck makes a run read (its records and PSD files, its RRS files), found by the
keys that name them: what a report lists with their checksums (rbhyst.files.provenance)."""

from __future__ import annotations

from pathlib import Path

from rbhyst.model.deck import Deck, Random, Record


def resolved(name: str, base: Path) -> Path:
    """A file named in a deck: absolute as given, or relative to the deck's folder."""
    return Path(name) if Path(name).is_absolute() else base / name


def deck_inputs(deck: Deck) -> list[tuple[str, Path, str]]:
    """(key, path, name as given) of the deck itself (where it came from a file) and of every
    file it names for the excitation and the qualification, in the deck's order."""
    out = [("deck", deck.source, deck.source.name)] if deck.source is not None else []
    ex = deck.excitation
    for part, name in ((ex.support if ex else None, "support"), (ex.force if ex else None, "force")):
        if part is None:
            continue
        for axis in type(part).model_fields:
            signal = getattr(part, axis)
            key = f"excitation.{name}.{axis}"
            if isinstance(signal, Record):
                out.append((f"{key}.file", resolved(signal.file, deck.base), signal.file))
            elif isinstance(signal, Random) and isinstance(signal.psd, str):
                out.append((f"{key}.psd", resolved(signal.psd, deck.base), signal.psd))
    q = deck.qualify
    for key in ("rrs", "rrs_x2", "rrs_x3") if q is not None else ():
        if getattr(q, key) is not None:
            out.append((f"qualify.{key}", resolved(getattr(q, key), deck.base), getattr(q, key)))
    return out
