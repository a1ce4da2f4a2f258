"""CSV text of a float table, byte for byte what "%.10g" % x gives, compiled.

Formatting 40,001 rows x 35 values with Python's % operator takes about 0.3 s; this takes
a small fraction of it. Each value is rounded to 10 significant digits in floating point;
where that rounding is within a few ulps of a tie (about 1 value in 10^5) the decimal
digits are taken from Python's correctly rounded formatting instead, so the text is always
exactly printf's. The compiled halves are in rbhyst.solve.kernels.csvfmt.
"""

from __future__ import annotations

import numpy as np

from rbhyst.solve.kernels.compiled import kernel
from rbhyst.solve.kernels.layout import DIGITS, TIE_MARGIN  # noqa: F401  (the formatter's own)
MAX_WIDTH = 17  # "-1.234567891e-308"
#: 10^k for k = -300..300: the formatter scales by table, not by pow
POW10 = np.array([float(f"1e{k}") for k in range(-300, 301)])


def format_rows(table: np.ndarray) -> bytes:
    """CSV lines of a 2-D float table, each value as "%.10g" would print it."""
    return bytes(RowsText()(table))


class RowsText:
    """format_rows for a stream of chunks of one width: the work arrays and the text buffer are
    kept from one chunk to the next (fresh ones cost a page fault every 4 kB, a tenth of the
    time of the formatting), and the text comes back as a view of the buffer, not a copy: use
    it before the next call."""

    def __init__(self):
        self._work: dict[str, np.ndarray] = {}

    def _array(self, name: str, size: int, dtype) -> np.ndarray:
        a = self._work.get(name)
        if a is None or a.size < size:
            a = self._work[name] = np.empty(size, dtype)
        return a[:size]

    def __call__(self, table: np.ndarray) -> memoryview:
        table = np.ascontiguousarray(table, dtype=float)
        if table.size == 0:
            return memoryview(b"\n" * table.shape[0])
        mant = self._array("mant", table.size, np.int64).reshape(table.shape)
        expo = self._array("expo", table.size, np.int64).reshape(table.shape)
        flag = self._array("flag", table.size, np.int8).reshape(table.shape)
        if kernel("decompose")(table, mant, expo, flag, POW10):
            for i, j in zip(*np.nonzero(flag == 1)):
                # exact decimal digits of a near-tie: "%.9e" rounds to the same 10 digits as "%.10g"
                digits, exponent = ("%.9e" % abs(table[i, j])).split("e")
                mant[i, j] = int(digits.replace(".", ""))
                expo[i, j] = int(exponent)
                flag[i, j] = 0
        buf = self._array("buf", table.shape[0] * (table.shape[1] * (MAX_WIDTH + 1) + 1), np.uint8)
        n = kernel("render")(table, mant, expo, flag, buf, self._array("digits", DIGITS, np.int64))
        return memoryview(buf)[:n]
