"""CSV text of a header and rows, as Python's csv module writes it (one line ending: \\n): as a
string, or streamed into a file row by row (the same bytes, without the whole text in memory)."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable


def to_csv(header: list[str], rows: list[list]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


def write_csv(path, header: list[str], rows: Iterable[list]) -> None:
    """The bytes of ``to_csv(header, rows)`` into ``path`` (UTF-8), the rows taken as they come."""
    with open(path, "w", encoding="utf-8", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)
