"""--save-histories: every case's time history in one Parquet file, ``histories.parquet``.

Parquet (through pyarrow, the optional extra ``rbhyst[histories]``) because a sweep's
histories are one long table: columnar, compressed, read by pandas, polars, DuckDB or
pyarrow one column or one case at a time without loading the rest, and pyarrow is one
wheel with nothing to compile. HDF5 or netCDF would need h5py or xarray and a fixed layout
per case. The file has a ``case`` column (cases.csv's numbering) then time_history.csv's
columns, one row group per case; a column a case does not have (another scene's elements)
is empty (null) there.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

EXTRA = "histories"


def require_pyarrow() -> None:
    from rbhyst.errors import InputError

    try:
        import pyarrow  # noqa: F401
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        raise InputError(f"--save-histories: needs pyarrow: pip install \"rbhyst[{EXTRA}]\"") from None


def write_part(path: Path, final: Path, histories: list[tuple[str, dict]]) -> None:
    """A batch's histories ((key, {"columns", "table"}) each), one row group per case, into
    ``path``, then renamed to ``final``. Cases with other columns (another scene's elements)
    get nulls in the columns they lack."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    columns = list(dict.fromkeys(c for _, h in histories for c in h["columns"]))
    schema = pa.schema([("key", pa.string())] + [(c, pa.float64()) for c in columns])
    with pq.ParquetWriter(path, schema, **_encoding("key", columns)) as writer:
        for key, h in histories:
            n = len(h["table"])
            index = {c: i for i, c in enumerate(h["columns"])}
            data = {"key": pa.array([key] * n, pa.string())}
            for c in columns:
                data[c] = pa.array(h["table"][:, index[c]]) if c in index else pa.nulls(n, pa.float64())
            writer.write_table(pa.table(data, schema=schema))
    os.replace(path, final)


def _encoding(label: str, columns: list[str]) -> dict:
    """zstd over byte-stream-split doubles (their exponent bytes side by side compress; whole
    doubles barely do): a third smaller than plain zstd, and faster; a dictionary for the label."""
    return {"compression": "zstd", "use_dictionary": [label], "use_byte_stream_split": list(columns)}


def assemble(out_file: Path, cases: list, parts: dict[str, Path]) -> int:
    """histories.parquet from the parts: each case (cases.csv order) whose key has a part, one
    row group each, ``case`` first and the union of the columns. Returns the rows written."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    files = list(dict.fromkeys(parts.values()))
    columns: list[str] = []
    for f in files:
        columns.extend(n for n in pq.read_schema(f).names if n != "key")
    columns = list(dict.fromkeys(columns))
    schema = pa.schema([("case", pa.int32())] + [(c, pa.float64()) for c in columns])
    numbers: dict[str, list[int]] = {}
    for c in cases:
        if c.key in parts:
            numbers.setdefault(c.key, []).append(c.number)
    by_part: dict[Path, list[str]] = {}
    for key in sorted(numbers, key=lambda k: numbers[k][0]):
        by_part.setdefault(parts[key], []).append(key)
    rows = 0
    with pq.ParquetWriter(out_file, schema, **_encoding("case", columns)) as writer:
        for f, keys in by_part.items():
            part = pq.read_table(f)  # one part (a batch) in memory at a time
            key_column = part.column("key").to_numpy(zero_copy_only=False)
            for key in keys:
                sub = part.filter(pa.array(key_column == key))
                n = sub.num_rows
                for number in numbers[key]:
                    data = {"case": pa.array(np.full(n, number, dtype=np.int32))}
                    for c in columns:
                        data[c] = sub.column(c) if c in sub.column_names else pa.nulls(n, pa.float64())
                    writer.write_table(pa.table(data, schema=schema))
                    rows += n
    return rows
