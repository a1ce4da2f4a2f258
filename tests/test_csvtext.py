"""time_history.csv's numbers are exactly what "%.10g" gives, however they are formatted."""

from __future__ import annotations

import errno
import threading
import time
from pathlib import Path

import numpy as np
import pytest

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


@pytest.mark.parametrize("piece_rows", [None, 1, 7, 700])
def test_a_file_streamed_chunk_by_chunk_is_the_table_s_text(tmp_path, piece_rows):
    """CsvWriter formats and writes the chunks in threads while the caller goes on (a chunk's
    pieces formatted two at once, written in turn): chunks of any size and stride, cut into
    pieces of any size (one row; an odd or even number of them; pieces larger than a chunk),
    in order, however many wait; called again, the file starts over (tolerance mode's ladder
    runs again into the same file)."""
    from rbhyst.results.writers import CsvWriter

    rng = np.random.default_rng(3)
    table = rng.standard_normal((9000, 5)) * 10.0 ** rng.integers(-8, 8, (9000, 5))
    path = tmp_path / "t.csv"
    w = CsvWriter(path)
    if piece_rows is not None:
        w.PIECE_VALUES = piece_rows * table.shape[1]
    w(("a", "b"))  # a first run that is started over
    w.add(table[:10, :2])
    w.close()
    w(("a", "b", "c", "d", "e"))
    cuts = [0, 1, 2, 700, 7001, 7002, 9000]
    for lo, hi in zip(cuts, cuts[1:]):
        w.add(table[lo:hi])
    w.add(table[::1000])  # a strided chunk, as output.every takes
    w.close()
    w.wait()
    expected = "a,b,c,d,e\n" + format_rows(table).decode() + format_rows(table[::1000]).decode()
    assert path.read_text() == expected


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_write_that_fails_in_the_writer_s_thread_is_raised_to_the_caller():
    """/dev/full fails every write with ENOSPC: the error reaches the caller (the next add or
    wait), never lost in the thread, and the file is closed all the same."""
    from rbhyst.results.writers import CsvWriter

    w = CsvWriter(Path("/dev/full"))(("a",))
    w.add(np.ones((50_000, 1)))  # (its write, in the thread, is the first that fails: the header is buffered)
    with pytest.raises(OSError) as caught:  # by the third add at the latest, which waits for the first
        w.add(np.ones((10, 1)))
        w.add(np.ones((10, 1)))
        w.close()
        w.wait()
    assert caught.value.errno == errno.ENOSPC
    w.close()
    with pytest.raises(OSError):
        w.wait()
    assert w._last is not None and not w._last.is_alive()


def test_the_compiled_formatter_lets_other_threads_run():
    """time_history.csv is formatted by a thread while the run steps: the formatting kernel
    (built ahead of time or numba's JIT) holds no lock of Python's while it runs. The calling
    thread's Python runs all through one long call (a kernel that kept the lock would leave
    it a few milliseconds at either end: a gap of most of the call, 74-87 % when measured)."""
    from rbhyst.results.csvtext import POW10
    from rbhyst.solve.kernels.compiled import kernel

    decompose = kernel("decompose")
    table = np.random.default_rng(1).standard_normal((150_000, 20))
    mant, expo = np.empty(table.shape, np.int64), np.empty(table.shape, np.int64)
    flag = np.empty(table.shape, np.int8)
    decompose(table[:10], mant[:10], expo[:10], flag[:10], POW10)  # (compiled before it is watched)
    span = []

    def call():
        span.append(time.perf_counter())
        decompose(table, mant, expo, flag, POW10)
        span.append(time.perf_counter())

    worker = threading.Thread(target=call)
    stamps = []
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())
    worker.join()
    t0, t1 = span
    seen = [t0] + [s for s in stamps if t0 < s < t1] + [t1]
    assert np.max(np.diff(seen)) < 0.5 * (t1 - t0), (t1 - t0, np.max(np.diff(seen)))


def test_the_figures_wait_for_the_csv_and_are_drawn_on_two_cores(tmp_path, monkeypatch):
    """A run's figures are drawn once time_history.csv's thread has ended, so that the process
    may still fork to draw them on two cores (it does not fork with a thread running): a disk
    slower than matplotlib's import must not make them serial."""
    import rbhyst
    import rbhyst.report.parallel as parallel
    from rbhyst.results.csvtext import RowsText
    from conftest import seed_deck, write_deck

    text = RowsText.__call__

    def slow(self, table):
        time.sleep(0.3)
        return text(self, table)

    seen = []
    fork_is_safe = parallel._fork_is_safe
    monkeypatch.setattr(RowsText, "__call__", slow)
    monkeypatch.setattr(parallel, "_fork_is_safe", lambda: seen.append(threading.active_count()) or fork_is_safe())
    deck = write_deck(tmp_path, seed_deck(duration=2.0))
    rbhyst.run(deck, out=tmp_path / "out", plots=True)
    assert seen and seen[0] == 1
    text = (tmp_path / "out" / "time_history.csv").read_text().splitlines()
    assert len(text) == 2002
