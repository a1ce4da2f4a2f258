"""The compiled halves of rbhyst.results.csvtext.format_rows: round to DIGITS significant digits, render.

They let go of Python's lock (nogil; built ahead of time, every kernel does): time_history.csv
is formatted by a thread while the run goes on (rbhyst.results.writers.CsvWriter)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rbhyst.solve.kernels.layout import DIGITS, TIE_MARGIN


@njit(cache=True, error_model="numpy", _nrt=False, nogil=True)
def _decompose(table, mant, expo, flag, p10):
    """Round every value to DIGITS significant digits: |x| = mant * 10^(expo - DIGITS + 1).

    flag = 1 where the rounding is too close to a tie to trust floating point, 2 for values
    printed as words (0, inf, nan). p10[k + 300] = 10^k for |k| <= 300 (a table: no pow, no log).
    Returns the number of flagged values.
    """
    n_flag = 0
    lo = 10.0 ** (DIGITS - 1)
    hi = 10.0 ** DIGITS
    for i in range(table.shape[0]):
        for j in range(table.shape[1]):
            x = table[i, j]
            ax = abs(x)
            if ax == 0.0 or not math.isfinite(x):
                flag[i, j] = 2
                mant[i, j] = 0
                expo[i, j] = 0
                continue
            # the decimal exponent from the binary one (off by one at most: corrected below)
            e = int(math.floor((math.frexp(ax)[1] - 1) * 0.30102999566398120))
            k = DIGITS - 1 - e
            # scale in two factors so that neither overflows for extreme exponents
            if k > 300:
                y = ax * 1e300 * p10[k]
            elif k < -300:
                y = ax * 1e-300 * p10[k + 600]
            else:
                y = ax * p10[k + 300]
            while y >= hi:
                e += 1
                y /= 10.0
            while y < lo:
                e -= 1
                y *= 10.0
            m = math.floor(y + 0.5)
            frac = y - math.floor(y)
            if abs(frac - 0.5) < TIE_MARGIN or y < lo * (1.0 - 1e-12) or m > hi:
                flag[i, j] = 1
                n_flag += 1
            else:
                flag[i, j] = 0
            if m >= hi:
                m = lo
                e += 1
            mant[i, j] = np.int64(m)
            expo[i, j] = e
    return n_flag


@njit(cache=True, error_model="numpy", _nrt=False, nogil=True)
def _put_int(buf, pos, value, width):
    """Write a non-negative integer with exactly ``width`` digits."""
    for k in range(width - 1, -1, -1):
        buf[pos + k] = 48 + value % 10
        value //= 10
    return pos + width


@njit(cache=True, error_model="numpy", _nrt=False, nogil=True)
def _render(table, mant, expo, flag, buf, digits):
    """Write the rows as CSV text (comma separated, newline terminated) into buf; returns bytes.
    digits: (DIGITS,) int64 work space.

    The digits come from multiplications and shifts, not divisions (a division costs tens of
    cycles, ten of them a value were most of the time of a run's CSV); every digit is written,
    then the end is set after the last significant one: the same text as writing only those,
    with fewer branches. Writes run up to 17 bytes past a value's start, within the room that
    the caller gives each value (MAX_WIDTH + 1).

    Long because it is one compiled loop over every value: the cases of a value's text are
    written in place rather than by calls, each of which would cost about as much as the text."""
    pos = 0
    for i in range(table.shape[0]):
        for j in range(table.shape[1]):
            if j > 0:
                buf[pos] = 44  # ","
                pos += 1
            x = table[i, j]
            if flag[i, j] == 2:
                if x == 0.0:
                    if math.copysign(1.0, x) < 0.0:
                        buf[pos] = 45
                        pos += 1
                    buf[pos] = 48
                    pos += 1
                elif math.isnan(x):
                    buf[pos] = 110
                    buf[pos + 1] = 97
                    buf[pos + 2] = 110
                    pos += 3
                else:
                    if x < 0.0:
                        buf[pos] = 45
                        pos += 1
                    buf[pos] = 105
                    buf[pos + 1] = 110
                    buf[pos + 2] = 102
                    pos += 3
                continue
            buf[pos] = 45  # "-", kept for a negative value only
            pos += x < 0.0
            m = mant[i, j]
            e = expo[i, j]
            # the DIGITS (10) digits as characters, five from each half of m
            hi = np.int64(m / 100000.0)  # exact: m < 2^34, so the quotient cannot round up to an integer
            half = m - hi * 100000
            for k in (5, 0):
                a = (half * 167773) >> 24  # half // 100 (half < 10^5)
                b = half - a * 100
                a2 = (a * 41) >> 12  # a // 100 (a < 1000)
                c = a - a2 * 100
                c1 = (c * 205) >> 11  # c // 10 (c < 100)
                b1 = (b * 205) >> 11
                digits[k] = 48 + a2
                digits[k + 1] = 48 + c1
                digits[k + 2] = 48 + c - c1 * 10
                digits[k + 3] = 48 + b1
                digits[k + 4] = 48 + b - b1 * 10
                half = hi
            last = DIGITS - 1  # last significant (non-zero) digit
            while last > 0 and digits[last] == 48:
                last -= 1
            if 0 <= e < DIGITS:  # ddd.ddd: the point after digit e
                buf[pos + e + 1] = 46
                for k in range(DIGITS):
                    buf[pos + k + (k > e)] = digits[k]
                pos += last + 2 if last > e else e + 1
            elif -4 <= e < 0:  # 0.000ddd
                buf[pos] = 48
                buf[pos + 1] = 46
                for k in range(4):
                    buf[pos + 2 + k] = 48
                for k in range(DIGITS):
                    buf[pos + 1 - e + k] = digits[k]
                pos += 2 - e + last
            else:  # d.ddde+XX
                buf[pos] = digits[0]
                buf[pos + 1] = 46
                for k in range(1, DIGITS):
                    buf[pos + 1 + k] = digits[k]
                pos += last + 2 if last > 0 else 1
                buf[pos] = 101  # "e"
                buf[pos + 1] = 45 if e < 0 else 43
                pos += 2
                ae = -e if e < 0 else e
                pos = _put_int(buf, pos, ae, 3 if ae >= 100 else 2)
        buf[pos] = 10
        pos += 1
    return pos
