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
