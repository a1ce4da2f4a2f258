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


#: values formatted per compiled call: the work arrays (16 bytes a value) stay in the cache and
#: are not faulted in afresh for every chunk's size
BLOCK_VALUES = 32_768


def format_rows(table: np.ndarray) -> bytes:
    """CSV lines of a 2-D float table, each value as "%.10g" would print it."""
    return bytes(RowsText()(table))


class RowsText:
    """format_rows for a stream of chunks of one width: the work arrays and the text buffer are
    kept from one chunk to the next (fresh ones cost a page fault every 4 kB, a tenth of the
    time of the formatting), and the text comes back as a view of the buffer, not a copy: use
    it before the next call. The compiled kernels are looked up when it is made, so that a
    thread can format with it; they let go of Python's lock while they run."""

    def __init__(self):
        self._work: dict[str, np.ndarray] = {}
        self._decompose, self._render = kernel("decompose"), kernel("render")

    def _array(self, name: str, size: int, dtype) -> np.ndarray:
        a = self._work.get(name)
        if a is None or a.size < size:
            a = self._work[name] = np.empty(size, dtype)
        return a[:size]

    def __call__(self, table: np.ndarray) -> memoryview:
        rows, cols = table.shape
        if table.size == 0:
            return memoryview(b"\n" * rows)
        buf = self._array("text", rows * (cols * (MAX_WIDTH + 1) + 1), np.uint8)
        digits = self._array("digits", DIGITS, np.int64)
        step = max(1, BLOCK_VALUES // cols)
        pos = 0
        for first in range(0, rows, step):
            part = np.ascontiguousarray(table[first:first + step], dtype=float)
            size = part.size
            mant = self._array("mant", size, np.int64).reshape(part.shape)
            expo = self._array("expo", size, np.int64).reshape(part.shape)
            flag = self._array("flag", size, np.int8).reshape(part.shape)
            if self._decompose(part, mant, expo, flag, POW10):
                for i, j in zip(*np.nonzero(flag == 1)):
                    # exact decimal digits of a near-tie: "%.9e" rounds to the same 10 digits as "%.10g"
                    digits_text, exponent = ("%.9e" % abs(part[i, j])).split("e")
                    mant[i, j] = int(digits_text.replace(".", ""))
                    expo[i, j] = int(exponent)
                    flag[i, j] = 0
            pos += self._render(part, mant, expo, flag, buf[pos:], digits)
        return memoryview(buf)[:pos]
