"""The figures as a reader sees them: titles apart, texts legible in print, legends beside the
data, axes labelled where their values are read (measured on matplotlib's layout after a draw:
tests/figure_checks.py)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from figure_checks import overlapping_titles, points_under_legend, smallest_print_pt, tick_values
from rbhyst.analyses.qualification.rrs import requested_rrs
from rbhyst.report.qualification import plot_verdict

KEYS = {k: k for k in ("rrs", "rrs_x2", "rrs_x3", "damping", "sds", "z_over_h", "level", "duration", "dt")}
G = 9.80665


def verdict_inputs(standard: str, space: bool, motions: int):
    """A standard's RRS per axis, each motion's TRS a little above it, and criteria (one over)."""
    if standard == "ac156":
        rrs, _ = requested_rrs("ac156", None, None, 1.0, 0.5, Path("."), KEYS, None, None, space)
    else:
        rrs, _ = requested_rrs("ieee693", None, None, None, None, Path("."), KEYS, "moderate", None, space)
    checks = {}
    for axis, r in rrs.items():
        f = np.geomspace(*r.check_range, 25)
        checks[axis] = [(f"TRS, motion {m + 1}", SimpleNamespace(frequency_hz=f, trs=r(f) * (1.05 + 0.03 * m),
                                                                 within=np.ones(25, bool))) for m in range(motions)]
    criteria = [{"label": f"force e{k}", "demand": 1000.0 * k, "capacity": 2.0e4, "unit": "N", "pass": True}
                for k in range(1, 9)] + [{"label": "acceleration top x1", "demand": 2.5, "capacity": 2.0,
                                          "unit": "g", "pass": False}]
    return checks, rrs, criteria


@pytest.mark.parametrize("standard, space, motions", [("ac156", False, 2), ("ac156", True, 7),
                                                      ("ieee693", False, 1), ("ieee693", True, 3)])
def test_the_qualification_figure_reads_in_print(tmp_path, standard, space, motions):
    checks, rrs, criteria = verdict_inputs(standard, space, motions)
    fig = plot_verdict(checks, rrs, criteria, False, tmp_path / "q.png", space=space,
                       title="Cabinet with a transformer on four wire rope isolators, qualified to AC156",
                       notes=("TRS within the band: yes", "estimated error 0.55 % (at most 1 %)", "warnings: none",
                              "the largest over the 2 motions (fewer than seven: ASCE 7-10 16.2.4)"))
    assert overlapping_titles(fig) == []
    assert smallest_print_pt(fig) >= 8.0  # (the bars' labels were 7 pt on a figure printed at 0.68)
    panels = [ax for ax in fig.axes if ax.get_yscale() == "log"]
    assert len(panels) == len(rrs)
    for ax, (axis, r) in zip(panels, rrs.items()):
        plateau = float(r(np.geomspace(*r.check_range, 400)).max()) / G
        ticks = tick_values(ax.yaxis)
        # a labelled tick on each side of the plateau, within a fifth of it: its value can be read
        assert any(plateau / 1.25 <= v <= plateau for v in ticks) and any(plateau < v <= 1.3 * plateau
                                                                            for v in ticks), (axis, ticks)
        assert f"{plateau:.3g} g" in [t.get_text() for t in ax.texts]
        assert points_under_legend(ax) == 0
