"""cases.csv and stats.csv from the cases and their results: pure functions.

Numbers are written exactly (Python's shortest repr, which reads back to the same double);
an empty cell is a value the case does not have (a failed run's peaks, a vary key another
listed case sets).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Iterator, Mapping, Sequence

import numpy as np

from rbhyst.analyses.sweep.cases import Case, format_value

#: the percentile stats.csv reports beside the median, by numpy's default (linear) rule
PERCENTILE = 84.0
#: the groups of a case's numbers and the prefix of their columns, in cases.csv's order
_PREFIX = {"peaks": "peak_", "stroke": "stroke_", "energy": "energy_", "accuracy": "accuracy_"}


def result_columns(entries: Iterable[dict | None]) -> list[str]:
    """peak_<column> for every peak of every result, then stroke_e<k> (the stroke utilization of
    each element with a stroke), energy_<key>, accuracy_<key>, each in the order first met (a
    scene with more elements adds its columns)."""
    groups: dict[str, dict[str, None]] = {g: {} for g in _PREFIX}
    for e in entries:
        if e and e.get("status") == "ok":
            for g, names in groups.items():
                names.update(dict.fromkeys(e.get(g) or {}))
    prefix = _PREFIX
    return [prefix[g] + n for g, names in groups.items() for n in names]


def case_status(case: Case, entry: dict | None) -> tuple[str, str]:
    if case.problem is not None:
        return "failed", case.problem
    if entry is None:
        return "missing", "not computed"
    return entry["status"], entry.get("message") or ""


class CaseRows(Sequence):
    """cases.csv's rows, each held as its line (the text Python's csv module writes for it, without
    the line ending) and read back into its cells where it is taken: a row of some 70 cells held
    as a list of strings took 4-5 kB, its line about 1.3 (a sweep of 10^5 cases keeps them all
    until its files are written). A row reads back as it was made: the case's number an int, every
    other cell its text."""

    def __init__(self, lines: list[str]):
        self.lines = lines

    def __len__(self) -> int:
        return len(self.lines)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return list(_cells(self.lines[i]))
        return next(_cells([self.lines[i]]))

    def __iter__(self) -> Iterator[list]:
        return _cells(self.lines)


def _cells(lines: Iterable[str]) -> Iterator[list]:
    for row in csv.reader(lines):
        row[0] = int(row[0])
        yield row


def write_case_rows(path, header: list[str], rows: CaseRows) -> None:
    """cases.csv from its header and rows: the bytes of ``to_csv(header, list(rows))``."""
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(_csv_text(header) + "\n")
        fh.writelines(line + "\n" for line in rows.lines)


def cases_table(cases: list[Case], vary_keys: list[str], results: dict[str, dict]) -> tuple[list[str], CaseRows]:
    """cases.csv: header and rows (one per case, in the sweep's order)."""
    entries = [None if c.problem else results.get(c.key) for c in cases]
    columns = result_columns(entries)
    header = ["case", "motion", "scale", *vary_keys, "status", "message", *columns]
    # each group's keys -> their cells (a case has the numbers of its groups; the others empty)
    where = {g: {c[len(prefix):]: i for i, c in enumerate(columns) if c.startswith(prefix)}
             for g, prefix in _PREFIX.items()}
    lines = []
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")  # (one writer, its line taken row by row)
    for c, e in zip(cases, entries):
        status, message = case_status(c, e)
        cells = [""] * len(columns)
        if e and e.get("status") == "ok":
            for g, at in where.items():
                for k, v in (e.get(g) or {}).items():
                    cells[at[k]] = _num(v)
        writer.writerow([c.number, c.motion, _num(c.scale),
                         *[format_value(c.vary[k]) if k in c.vary else "" for k in vary_keys],
                         status, message, *cells])
        lines.append(buf.getvalue()[:-1])
        buf.seek(0)
        buf.truncate()
    return header, CaseRows(lines)


STATS_HEADER = ("scale", "peak", "count", "failed", "mean", "median", "p84", "max")
#: stats.csv is made this many groups at a time: its rows are written as they come
GROUPS_AT_ONCE = 1000


def stats_table(cases: list[Case], vary_keys: list[str], results: dict[str, dict]) -> tuple[list[str], list[list]]:
    """stats.csv as a header and rows of its cells (text), as a reader of the file sees them."""
    rows = list(csv.reader(io.StringIO("".join(stats_lines(cases, vary_keys, results)))))
    return stats_header(vary_keys), rows


def stats_header(vary_keys: list[str]) -> list[str]:
    return [STATS_HEADER[0], *vary_keys, *STATS_HEADER[1:]]


def write_stats(path, cases: list[Case], vary_keys: list[str], results: dict[str, dict],
                known: Mapping[str, list[str]] | None = None) -> None:
    """stats.csv: for each scale level and vary combination, over its motions, the count of
    finished runs, the failed ones, and mean, median, 84th percentile (numpy's linear
    interpolation between order statistics) and max of every peak; the bytes Python's csv
    module writes (one line ending: \\n), a few groups at a time in memory. ``known``: see
    stats_lines."""
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(_csv_text(stats_header(vary_keys)) + "\n")
        for lines in stats_lines(cases, vary_keys, results, known):
            fh.write(lines)


class PeakCells(Mapping):
    """Each case's peak cells in cases.csv, by case key, read from its row where asked."""

    def __init__(self, rows: Sequence, keys: list[str], lo: int, hi: int):
        self._rows, self._lo, self._hi = rows, lo, hi
        self._at = {k: i for i, k in enumerate(keys)}

    def __getitem__(self, key: str) -> list[str]:
        return self._rows[self._at[key]][self._lo:self._hi]

    def __iter__(self) -> Iterator[str]:
        return iter(self._at)

    def __len__(self) -> int:
        return len(self._at)


def peak_cells(header: list[str], rows: Sequence, cases: list[Case]) -> Mapping[str, list[str]]:
    """Each case's peak cells in cases.csv (cases_table's header and rows), by case key."""
    at = [i for i, h in enumerate(header) if h.startswith(_PREFIX["peaks"])]
    if not at:
        return {}
    return PeakCells(rows, [c.key for c in cases[:len(rows)]], at[0], at[-1] + 1)


def stats_lines(cases: list[Case], vary_keys: list[str], results: dict[str, dict],
                known: Mapping[str, list[str]] | None = None) -> Iterator[str]:
    """stats.csv's lines after its header, GROUPS_AT_ONCE groups' at a time.

    Written as text, not as rows for the csv module: a sweep of 10,000 cases has 370,000 rows,
    and a list of cells for each was most of the 2.7 s its tables took after the last case.
    ``known`` (peak_cells): the text of each case's peaks in cases.csv, which a group of one
    finished case repeats as its mean, median, p84 and max without formatting them again, where
    numpy's statistics of one value are that value (a float, finite, not -0.0)."""
    entries = {c.key: (None if c.problem else results.get(c.key)) for c in cases}
    peaks = [c for c in result_columns(entries.values()) if c.startswith("peak_")]
    groups: dict[tuple, list[Case]] = {}
    for c in cases:
        ident = (c.scale, tuple(format_value(c.vary[k]) if k in c.vary else "" for k in vary_keys))
        groups.setdefault(ident, []).append(c)
    items = list(groups.items())
    peak_texts = [_csv_text([p]) for p in peaks]
    for first in range(0, len(items), GROUPS_AT_ONCE):
        yield _stats_lines(items[first:first + GROUPS_AT_ONCE], entries, peaks, peak_texts, known or {})


def _stats_lines(groups: list[tuple[tuple, list[Case]]], entries: dict, peaks: list[str],
                 peak_texts: list[str], known: Mapping[str, list[str]]) -> str:
    # every member's peaks in one matrix (have: the case finished and has that peak; floats:
    # every peak it has is a float, whose cell in cases.csv is its repr, not an int's text)
    names = [p[len(_PREFIX["peaks"]):] for p in peaks]
    members = [c for _, ms in groups for c in ms]
    values = np.zeros((len(members), len(peaks)))
    have = np.zeros((len(members), len(peaks)), dtype=bool)
    floats = [True] * len(members)
    failed_of, first = [], 0
    for _, ms in groups:
        failed = 0
        for c in ms:
            status = case_status(c, entries[c.key])[0]
            failed += status == "failed"
            if status == "ok":
                got = entries[c.key].get("peaks") or {}
                for j, name in enumerate(names):
                    v = got.get(name)
                    if v is not None:
                        values[first, j], have[first, j] = v, True
                        floats[first] = floats[first] and type(v) is float
            first += 1
        failed_of.append(failed)
    # every (group, peak) with as many values at once, a row of a matrix each: the same numbers
    # as one call per group (numpy reduces each row as it would the row alone), without a numpy
    # call per group and peak, which cost seconds at 10,000 groups. A group whose members all
    # have every peak goes whole into its size's matrix (a sweep of a continuous value: every
    # group is one case); the (group, peak) pairs of the others one by one
    by_count: dict[int, tuple[list[int], list[np.ndarray]]] = {}  # count -> rows, their values
    whole: dict[int, tuple[list[int], list[np.ndarray]]] = {}  # size -> first rows, (size, peaks) values
    heads: list[str] = []  # each row's text before its statistics (the whole line where it has them)
    complete = have.all(axis=1)
    # numpy's statistics of one value are that value where it is finite and not -0.0 (the mean
    # of -0.0 is 0.0, the p84 of inf is nan): a case's own peaks as they are in cases.csv
    as_is = np.array(floats) & np.isfinite(values).all(axis=1) & ~((values == 0.0) & np.signbit(values)).any(axis=1)
    first = 0
    for ((level, vary), ms), failed in zip(groups, failed_of):
        span = slice(first, first + len(ms))
        first += len(ms)
        head = _csv_text([_num(level), *vary]) + ","
        at = len(heads)
        cells = known.get(ms[0].key) if len(ms) == 1 and complete[span.start] and as_is[span.start] else None
        if cells is not None and len(cells) == len(peaks):
            heads.extend(f"{head}{p},1,{failed},{t},{t},{t},{t}\n" for p, t in zip(peak_texts, cells))
            continue
        if complete[span].all():
            starts, blocks = whole.setdefault(len(ms), ([], []))
            starts.append(at)
            blocks.append(values[span])
            tail = f",{len(ms)},{failed},"
            heads.extend(head + p + tail for p in peak_texts)
            continue
        for j, p in enumerate(peak_texts):
            x = values[span, j][have[span, j]]
            rows_n, xs = by_count.setdefault(len(x), ([], []))
            rows_n.append(len(heads))
            xs.append(x)
            heads.append(f"{head}{p},{len(x)},{failed},")
    batches = [([s + j for s in starts for j in range(len(peaks))],  # (group, peak) in order, peaks within
                np.stack(blocks).transpose(0, 2, 1).reshape(len(starts) * len(peaks), n))
               for n, (starts, blocks) in whole.items()]
    batches += [(at, np.array(xs, dtype=float).reshape(len(xs), n)) for n, (at, xs) in by_count.items()]
    lines = heads  # (the rows below get their statistics; the others are whole)
    for at, x in batches:
        s = peak_stats(x)
        if x.shape[1] == 0:
            for i in at:
                lines[i] = heads[i] + ",,,\n"
            continue
        for i, stats in zip(at, zip(s["mean"], s["median"], s["p84"], s["max"])):
            lines[i] = heads[i] + _stats_text(*stats)
    return "".join(lines)


def _stats_text(mean: float, median: float, p84: float, top: float) -> str:
    """The four statistics' cells and the line's end, each value exactly (its repr); a value
    equal to the one before is formatted once (a group of one case, or of equal peaks, has all
    four alike), but 0.0 and -0.0, equal, are each written as they are."""
    a = repr(mean)
    b = a if median == mean and median != 0.0 else repr(median)
    c = b if p84 == median and p84 != 0.0 else repr(p84)
    d = c if top == p84 and top != 0.0 else repr(top)
    return f"{a},{b},{c},{d}\n"


def _csv_text(fields: list) -> str:
    """The cells as one line of Python's csv module, without its line ending (a cell with a
    comma, a quote or a line break quoted)."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(fields)  # (its line ending is what it quotes for)
    return buf.getvalue()[:-1]


def peak_stats(x: np.ndarray) -> dict[str, list[float | None]]:
    """mean, median, p84 and max of each row of ``x`` (rows, values)."""
    if x.shape[1] == 0:
        return dict.fromkeys(("mean", "median", "p84", "max"), [None] * len(x))
    return {"mean": np.mean(x, axis=1).tolist(), "median": np.median(x, axis=1).tolist(),
            "p84": np.percentile(x, PERCENTILE, axis=1).tolist(), "max": np.max(x, axis=1).tolist()}


def _num(v) -> str:
    if v is None:
        return ""
    return repr(float(v)) if isinstance(v, float) else str(v)
