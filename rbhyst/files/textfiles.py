"""Reading the user's text files (decks, records, measured loops) with one-line errors."""

from __future__ import annotations

from pathlib import Path

from rbhyst.errors import InputError


def read_text(path: Path, encoding: str = "utf-8-sig") -> str:
    """The file's text; a missing, unreadable or binary file is an InputError naming it. UTF-8
    with or without a byte-order mark (Windows Notepad writes one): the mark is not text."""
    try:
        return Path(path).read_text(encoding=encoding)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot be read ({exc.__class__.__name__})") from None


def is_number(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True
