"""Runs that are long or fast: memory bounded for every excitation, the size of a large output
said before it starts, progress on a terminal, and a note where dt cannot show the response."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import textwrap
import time

import pytest

import rbhyst
from rbhyst.terminal import Progress
from conftest import square_linear_deck, write_deck

#: a random valid scene that once allocated 31 million samples of a 113 Hz load (708 MiB, then the
#: operating system's killer): a 5-vertex body, 3 elements, p1 and m3 at 113 Hz, dt = 0.01 s, 13.5 s
FAST_FORCE = textwrap.dedent("""
    [body]
    vertices = [[-0.42486, 0.022018], [-0.432579, -0.032586], [-0.340032, -0.191082], [-0.191643, -0.067105], [-0.446679, 0.148558]]
    mass = 21.867
    [hysteresis.s1]
    loading = { kb = 213137.0, f0 = 42.6275, alpha = 24999.9 }
    unloading = { kb = 106568.0, f0 = 153.459, alpha = 20833.3 }
    [[elements]]
    point = [-0.17604, 0.076761]
    angle_deg = 288.51
    hysteresis = "s1"
    count = 3
    [[elements]]
    vertex = 3
    angle_deg = -90.0
    hysteresis = "s1"
    [[elements]]
    vertex = 2
    angle_deg = 279.03
    hysteresis = "s1"
    count = 2
    [excitation.force]
    point = [-0.46772, -0.12634]
    p1 = { type = "sine", amplitude = 0.0812856, frequency_hz = 113.181, units = "kN" }
    m3 = { type = "sine", amplitude = 6.87338, frequency_hz = 113.181, units = "N m" }
    [analysis]
    dt = 0.01
    duration = 13.5
""")

MEASURE = r"""
import resource, subprocess, sys, time
tic = time.perf_counter()
done = subprocess.run([sys.executable, "-m", "rbhyst.cli", "run", sys.argv[1], "--no-plots"], capture_output=True, text=True)
print(done.returncode, time.perf_counter() - tic, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
print(done.stderr)
"""


def test_a_fast_force_over_a_long_run_stays_within_a_gibibyte_and_two_minutes(tmp_path):
    deck = tmp_path / "fast.toml"
    deck.write_text(FAST_FORCE)
    out = subprocess.run([sys.executable, "-c", MEASURE, str(deck)], capture_output=True, text=True, check=True,
                         cwd=tmp_path).stdout
    first, stderr = out.split("\n", 1)
    code, wall, rss_kib = first.split()
    assert int(code) == 0, stderr
    assert float(wall) < 120.0
    assert int(rss_kib) < 1024 * 1024, rss_kib  # ru_maxrss is in KiB on Linux
    # the rows at dt = 10 ms cannot show a 113 Hz response, and the run says what would
    assert "excitation.force.p1, excitation.force.m3: a 113.2 Hz sine spans 0.88 rows of dt = 0.01 s" in stderr
    assert "dt = 0.000884 s (10 rows) would show it" in stderr


class Listener:
    def __init__(self):
        self.events = []

    def note(self, text):
        self.events.append(("note", text))

    def update(self, done, total, label=""):
        self.events.append(("update", label))


def test_a_large_output_is_said_before_the_run_starts(tmp_path, monkeypatch):
    """Beyond 1 GB the run says so before it starts, with the output.every that keeps the CSV
    under 100 MB (here both limits a hundredth as large, so that the test writes 0.1 GB, not 1)."""
    import rbhyst.solve.plan as sim

    monkeypatch.setattr(sim, "LARGE_CSV_BYTES", 1e7)
    monkeypatch.setattr(sim, "SMALL_CSV_BYTES", 1e6)
    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.1, "frequency_hz": 2.0, "units": "g"}}}
    data["analysis"].update(dt=1e-4, duration=20.0, estimate_error=False)  # 200,001 rows of 30 columns
    listener = Listener()
    res = rbhyst.run(write_deck(tmp_path, data), out=tmp_path / "out", plots=False, monitor=listener)
    kind, text = listener.events[0]
    assert kind == "note" and text.startswith("output: time_history.csv will take about 0.096 GB (2e+05 rows of "
                                              "30 columns); output.every = 96 keeps it under 1 MB")
    assert listener.events[1] == ("update", "chang: time stepping") and text in res.notes
    size = (tmp_path / "out" / "time_history.csv").stat().st_size
    assert 0.5 < size / 96e6 < 1.0  # the estimate holds (about 16 bytes a value, at most)


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_shows_only_on_a_terminal_and_only_after_a_while():
    quiet = Progress(after=0.0, stream=io.StringIO())  # not a terminal
    quiet.update(1, 10, "time stepping")
    quiet.close()
    assert not quiet.shown and quiet.stream.getvalue() == ""
    early = Progress(after=60.0, stream=FakeTerminal())  # a quick command
    early.update(1, 10, "time stepping")
    early.close()
    assert not early.shown and early.stream.getvalue() == ""
    late = Progress(after=0.0, stream=FakeTerminal())
    late.update(3, 10, "time stepping")
    late.update(0, 0, "estimating the error")  # a phase of unknown length
    late.close()
    assert late.shown and "time stepping" in late.stream.getvalue()
