"""time_history.csv's numbers are exactly what "%.10g" gives, however they are formatted."""

from __future__ import annotations

import numpy as np

from rbhyst.results.csvtext import format_rows


def test_every_value_is_printf_s_10_significant_digits():
    rng = np.random.default_rng(7)
    edge = [0.0, -0.0, 1.0, 10.0, 1e10, 9999999999.5, 99999999995.0, 0.5, 1.5, 2.5, 123456789.5, 1e-5, 1e-4,
            0.0001234567895, 1e300, -1e-300, 5e-324, 2.2e-308, 1.7976931348623157e308, 1e22, 1e23, 0.1, 0.3,
            12345678905.0, 1234567890.5, np.inf, -np.inf, np.nan, 9.9999999995, 99999.999995, 1e-310, 3e-320]
    vals = np.concatenate([rng.standard_normal(30000) * 10.0 ** rng.integers(-300, 300, 30000), edge,
                           np.round(rng.standard_normal(20000) * 1e6) / 1e4 + 0.00005,  # near ties
                           rng.standard_normal(20000)])
    table = vals[: len(vals) // 7 * 7].reshape(-1, 7)
    expected = "".join(",".join("%.10g" % x for x in row) + "\n" for row in table)
    assert format_rows(table).decode() == expected
    assert format_rows(np.asfortranarray(table)).decode() == expected  # a column-major chunk too


def test_every_length_of_digits_at_every_place_of_the_point():
    """The renderer writes all ten digits and then cuts after the last significant one: each
    count of significant digits, 1 to 10, at each exponent of the plain and the e-notation forms."""
    digits = [int("1234567891"[:n]) for n in range(1, 11)] + [int("9" * n) for n in range(1, 11)]
    vals = [sign * d * 10.0 ** (e - len(str(d)) + 1) for d in digits for e in range(-7, 13) for sign in (1, -1)]
    table = np.array(vals).reshape(-1, 10)
    expected = "".join(",".join("%.10g" % x for x in row) + "\n" for row in table)
    assert format_rows(table).decode() == expected
