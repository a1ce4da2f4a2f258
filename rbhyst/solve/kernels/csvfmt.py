"""The compiled halves of rbhyst.results.csvtext.format_rows: round to DIGITS significant digits, render."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rbhyst.solve.kernels.layout import DIGITS, TIE_MARGIN


@njit(cache=True, error_model="numpy", _nrt=False)
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


@njit(cache=True, error_model="numpy", _nrt=False)
def _put_int(buf, pos, value, width):
    """Write a non-negative integer with exactly ``width`` digits."""
    for k in range(width - 1, -1, -1):
        buf[pos + k] = 48 + value % 10
        value //= 10
    return pos + width


@njit(cache=True, error_model="numpy", _nrt=False)
def _render(table, mant, expo, flag, buf, digits):
    """Write the rows as CSV text (comma separated, newline terminated) into buf; returns bytes.
    digits: (DIGITS,) int64 work space."""
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
            if x < 0.0:
                buf[pos] = 45
                pos += 1
            m = mant[i, j]
            e = expo[i, j]
            for k in range(DIGITS - 1, -1, -1):
                digits[k] = m % 10
                m //= 10
            last = DIGITS - 1  # last significant (non-zero) digit
            while last > 0 and digits[last] == 0:
                last -= 1
            if -4 <= e < DIGITS:
                if e >= 0:
                    for k in range(e + 1):
                        buf[pos] = 48 + digits[k]
                        pos += 1
                    if last > e:
                        buf[pos] = 46
                        pos += 1
                        for k in range(e + 1, last + 1):
                            buf[pos] = 48 + digits[k]
                            pos += 1
                else:
                    buf[pos] = 48
                    buf[pos + 1] = 46
                    pos += 2
                    for k in range(-e - 1):
                        buf[pos] = 48
                        pos += 1
                    for k in range(last + 1):
                        buf[pos] = 48 + digits[k]
                        pos += 1
            else:
                buf[pos] = 48 + digits[0]
                pos += 1
                if last > 0:
                    buf[pos] = 46
                    pos += 1
                    for k in range(1, last + 1):
                        buf[pos] = 48 + digits[k]
                        pos += 1
                buf[pos] = 101  # "e"
                buf[pos + 1] = 45 if e < 0 else 43
                pos += 2
                ae = -e if e < 0 else e
                pos = _put_int(buf, pos, ae, 3 if ae >= 100 else 2)
        buf[pos] = 10
        pos += 1
    return pos
