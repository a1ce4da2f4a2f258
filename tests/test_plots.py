"""What the figures show, read from their artists (never from pixels): the measured loop above
the fit, plain tick labels, no panel of numerical noise, the Nyquist frequency of a record,
legends for what is marked, lines that do not hide each other, units on every axis."""

from __future__ import annotations

import numpy as np
import pytest

from rbhyst.calibration import loop_result
from rbhyst.hysteresis import parameter_set


def _line(ax, label):
    found = [ln for ln in ax.get_lines() if ln.get_label() == label]
    assert len(found) == 1, [ln.get_label() for ln in ax.get_lines()]
    return found[0]


# ---------------------------------------------------------------- loops.png


def test_measured_loop_is_drawn_over_the_fit_as_markers(tmp_path):
    from rbhyst.report.loops import plot_loops

    p = parameter_set({"kb": 2e5, "f0": 1e3, "alpha": 700.0}, {"kb": 2e5, "f0": 1e3, "alpha": 700.0})
    u = 0.01 * np.sin(np.linspace(0.0, 4 * np.pi, 2001))
    clean = loop_result("s", p, u).f
    res = loop_result("s", p, u, clean + np.random.default_rng(1).normal(0.0, 20.0, u.size))
    fig = plot_loops([res], tmp_path / "loops.png", initial={"s": p})
    ax = fig.axes[0]
    data, fit = _line(ax, "test data"), _line(ax, "VRM fit")
    assert data.get_zorder() > fit.get_zorder()
    assert data.get_marker() not in (None, "None", "", " ") and data.get_linestyle() in ("None", "", " ")
    assert data.get_color() != fit.get_color()
    assert (tmp_path / "loops.png").stat().st_size > 0


# ---------------------------------------------------------------- transmissibility.png


class _Stepped:
    """What plot_transmissibility reads of a stepped-sine result."""

    direction = "x1"
    columns = ("T_G_x1", "T_G_x2", "T_top_x1", "T_top_x2")

    def __init__(self, frequencies):
        f = np.asarray(frequencies, float)
        t = 1.0 / np.abs(1.0 - (f / 8.0) ** 2 + 0.1j * f / 8.0)
        self._table = np.column_stack([f, np.full(f.size, 0.98), t, 1e-3 * t, 1.2 * t, 0.05 * t])

    def table(self):
        return self._table


def _tick_texts(ax):
    return [t.get_text() for axis in (ax.xaxis, ax.yaxis)
            for t in axis.get_ticklabels(which="both") if t.get_text()]


@pytest.mark.parametrize("frequencies", [np.geomspace(2.0, 20.0, 7), np.geomspace(0.5, 50.0, 12)])
def test_transmissibility_ticks_are_plain_numbers(tmp_path, frequencies):
    from rbhyst.report.transmissibility import plot_transmissibility

    fig = plot_transmissibility(_Stepped(frequencies), tmp_path / "t.png", title="a square")
    for ax in fig.axes:
        texts = _tick_texts(ax)
        assert texts, "no tick labels"
        assert not [t for t in texts if any(s in t for s in ("10^", "times", "×", "$"))], texts
        for t in texts:
            float(t.replace("\N{MINUS SIGN}", "-"))  # each a number as written
    if frequencies[-1] / frequencies[0] < 20:  # within about a decade: 2, 3, 5 ... are labelled
        assert "2" in [t.get_text() for t in fig.axes[0].xaxis.get_ticklabels(which="both")]
