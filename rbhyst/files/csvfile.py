"""CSV text of a header and rows, as Python's csv module writes it (one line ending: \\n)."""

from __future__ import annotations

import csv
import io


def to_csv(header: list[str], rows: list[list]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()
