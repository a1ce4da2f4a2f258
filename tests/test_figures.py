"""The figures as a reader sees them: titles apart, texts legible in print, legends beside the
data, axes labelled where their values are read (measured on matplotlib's layout after a draw:
tests/figure_checks.py)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from matplotlib.text import Text

from figure_checks import drawn, overlapping_titles, points_under_legend, smallest_print_pt, tick_values
from rbhyst.analyses.qualification.rrs import requested_rrs
from rbhyst.analyses.qualification.matching import Check
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
        checks[axis] = [(f"TRS, motion {m + 1}", Check(f, r(f), r(f) * (1.05 + 0.03 * m), r.band))
                        for m in range(motions)]
    criteria = [{"label": f"force e{k}", "demand": 1000.0 * k, "capacity": 2.0e4, "unit": "N", "pass": True}
                for k in range(1, 9)] + [{"label": "acceleration top x1", "demand": 2.5, "capacity": 2.0,
                                          "unit": "g", "pass": False}]
    return checks, rrs, criteria


@pytest.mark.parametrize("standard, space, motions", [("ac156", True, 7), ("ieee693", False, 1)])
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


# ------------------------------------------------------------------ a run's figures


@pytest.fixture(scope="module")
def shock(tmp_path_factory):
    """A 10 g, 11 ms half-sine along x2 at 0.05 s of a 0.6 s run, a point at a corner."""
    import rbhyst
    from conftest import write_deck
    from test_accelerations import pulse_deck

    d = pulse_deck("half-sine")
    d["output"] = {"points": [{"name": "P4", "point": [0.5, 0.5]}]}
    return rbhyst.run(write_deck(tmp_path_factory.mktemp("shock"), d), estimate=False)


def test_a_shock_s_support_motion_is_drawn_over_its_pulse_and_only_where_there_is_one(shock, tmp_path):
    from rbhyst.report.run import plot_excitation

    fig = plot_excitation(shock, tmp_path / "s.png")
    (ax,) = fig.axes  # no empty ag1 panel
    assert ax.get_ylabel().startswith("ag2") and "none along x1" in ax.get_title()
    lo, hi = ax.get_xlim()
    assert lo <= 0.05 and hi >= 0.061 and hi - lo <= 3 * 0.011  # the pulse fills the axis
    (line,) = ax.lines
    assert max(line.get_ydata()) == pytest.approx(10 * G, rel=1e-5)  # the signal's own peak, not the rows'
    assert overlapping_titles(fig) == []


def test_displacements_are_drawn_in_mm_without_an_offset(shock, tmp_path):
    from figure_checks import drawn
    from rbhyst.report.run import plot_point, plot_response

    for fig in (plot_response(shock, 1, tmp_path / "r.png"), plot_point(shock, "P4", tmp_path / "p.png")):
        drawn(fig)
        shown = [ax for ax in fig.axes if ax.get_ylabel().startswith("u2")]
        assert shown and all(ax.get_ylabel() == "u2 [mm]" for ax in shown)
        for ax in shown:
            assert ax.yaxis.get_offset_text().get_text() == ""  # no "1e-3" above the axis
            top = max(abs(y) for line in ax.lines for y in line.get_ydata())
            peak = shock.extremes.peak("u2_m" if fig.axes[0] is ax else "P4_u2_m")
            assert top == pytest.approx(1e3 * peak, rel=1e-9)


def test_the_energy_legend_is_beside_the_curves(shock, tmp_path):
    from figure_checks import drawn
    from rbhyst.report.run import plot_energy

    fig = drawn(plot_energy(shock, tmp_path / "e.png"))
    ax = fig.axes[0]
    box = ax.get_legend().get_window_extent(fig.canvas.get_renderer())
    assert points_under_legend(ax) == 0 and box.x0 > ax.get_window_extent().x1  # beside, not on, the input
    assert box.x1 <= fig.bbox.x1 and box.y0 >= fig.bbox.y0  # and whole on the figure


def test_loops_set_their_own_axis_not_the_strokes(tmp_path):
    """+-5 mm loops under +-60 mm strokes fill their panel, the strokes said in the legend; a
    stroke within reach (+5 mm of a 14 mm loop) is drawn."""
    import rbhyst
    from conftest import square_linear_deck, write_deck
    from rbhyst.report.run import plot_element_loops

    d = square_linear_deck()
    branch = {"kb": 2e5, "f0": 300.0, "alpha": 800.0, "beta1": 0.0, "beta2": 0.0}
    d["hysteresis"] = {"w": {"loading": branch, "unloading": branch}}
    for e in d["elements"]:
        e.update(hysteresis="w", stroke=0.06)
    d["elements"][2]["stroke"] = [-0.06, 0.005]
    d["excitation"] = {"support": {
        "x1": {"type": "sine", "amplitude": 0.3, "frequency_hz": 3.0, "units": "g", "cycles": 4},
        "x2": {"type": "sine", "amplitude": 0.3, "frequency_hz": 4.0, "units": "g", "cycles": 4}}}
    d["analysis"] = {"dt": 0.001, "duration": 2.0}
    res = rbhyst.run(write_deck(tmp_path, d), estimate=False)
    fig = plot_element_loops(res, tmp_path / "l.png")
    for k, ax in enumerate(fig.axes[:4], start=1):
        e = res.extremes
        i = res.columns.index(f"e{k}_u_m")
        span = 1e3 * (e.max[i] - e.min[i])
        lo, hi = ax.get_xlim()
        assert lo <= 1e3 * e.min[i] and hi >= 1e3 * e.max[i]
        texts = " ".join(t.get_text() for t in ax.get_legend().get_texts())
        if k == 3:
            assert span > 20 and lo <= 5.0 <= hi and "one beyond the axis" in texts
            assert any(list(line.get_xdata()) == [5.0, 5.0] for line in ax.lines)
        else:
            assert 5 < span < 40 and hi - lo <= 1.3 * span and "beyond the axis" in texts  # (strokes span 120 mm)


def test_spectra_keep_g_in_sight_and_break_their_title_between_phrases(tmp_path):
    """G's curve is a band under the points' lines (a point moving nearly as G does would hide
    a line of G's width); the title's lines break after a clause or before a parenthesis, never
    inside "sa at most 3.7e-14 m/s²"."""
    from rbhyst.report.spectra import plot_spectra
    from test_plots import _pulse_along_x2

    spectra = _pulse_along_x2(tmp_path)
    fig = plot_spectra(spectra, tmp_path / "spectra.png",
                       title="a cabinet on four wire rope isolators under a 10 g half-sine pulse of 11 ms along x2")
    ax = fig.axes[0]
    lines = {line.get_label(): line for line in ax.lines}
    g, top = lines["G (mass centre)"], lines["top"]
    assert g.get_zorder() < top.get_zorder() and g.get_linewidth() >= 2.5 * top.get_linewidth()
    title = fig._suptitle.get_text().split("\n")
    assert len(title) >= 3 and "sa at most" in " ".join(title)
    for line, after in zip(title, title[1:]):  # (each of the title's own lines starts one)
        assert line.endswith((":", ",", ";")) or after.startswith(("(", "damping", "no response")), title
    assert overlapping_titles(fig) == []


# ------------------------------------------------------------------ the analyses' figures


def test_measured_loops_are_drawn_as_loops_not_a_cloud(tmp_path):
    """The test data a line through every point in the order measured, markers on some."""
    from conftest import DECKS
    from rbhyst.analyses.calibration import loop_result, protocol
    from rbhyst.model.deck import Loops, load_deck
    from rbhyst.report.loops import plot_loops

    deck = load_deck(DECKS / "seed_fig4_loops.toml")
    _, u = protocol(Loops(amplitude=[0.004, 0.008], cycles=2, points_per_cycle=400))
    p = deck.hysteresis["wri_shear"].array()
    measured = loop_result("s", p, u).f * 1.05
    fig = plot_loops([loop_result("wri_shear", p, u, measured)], tmp_path / "loops.png")
    (data,) = [line for line in fig.axes[0].lines if line.get_label() == "test data"]
    assert data.get_linestyle() not in ("None", "none", "") and data.get_linewidth() > 0
    assert len(data.get_xdata()) == len(u)  # every point joined, in order
    assert np.allclose(data.get_ydata(), measured * 1e-3)


def test_transmissibility_s_legend_is_under_the_panels(tmp_path):
    from figure_checks import drawn
    from rbhyst.report.transmissibility import plot_transmissibility

    f = np.geomspace(0.5, 20.0, 8)
    table = np.array([[fi, a, 1.0 / abs(1 - (fi / 5.0) ** 2 + 0.1j * fi / 5.0), 1e-3 * fi]
                      for a in (0.5, 2.0) for fi in f])
    result = SimpleNamespace(table=lambda: table, columns=["T_G_x1", "T_G_x2"], direction="x1")
    fig = drawn(plot_transmissibility(result, tmp_path / "t.png", title="a cabinet"))
    ax = fig.axes[0]
    assert ax.get_legend() is None and len(fig.legends) == 1
    box = fig.legends[0].get_window_extent(fig.canvas.get_renderer())
    assert box.y1 <= ax.get_window_extent().y0  # under the panel, covering no curve
    assert len(fig.legends[0].get_texts()) == 4  # two amplitudes, along and across


def test_fragility_draws_every_stripe_s_count_and_names_an_unfitted_combination(tmp_path):
    """Two vary combinations, one fitted, one not: each stripe's count (3/7) is written for both,
    and the unfitted one's markers have their legend entry."""
    from rbhyst.report.fragility import plot_fragility

    state = SimpleNamespace(name="LS1", quantity="peak_at1_m_s2", limit=5.0)
    x = np.array([0.2, 0.4, 0.6])
    common = dict(limit_state=state, x=x, n=np.array([7, 7, 7]), band=None, identified=0,
                  grid=np.linspace(0.01, 0.8, 50))
    fitted = SimpleNamespace(group=(1,), fitted=True, median=0.4, beta=0.3, message="", z=np.array([1, 3, 6]),
                             **common)
    refused = SimpleNamespace(group=(2,), fitted=False, median=None, beta=None, z=np.array([0, 0, 0]),
                              message="no case reaches it", **common)
    fig = plot_fragility([fitted, refused], "Sa [g]", ["body.mass"], tmp_path / "f.png")
    ax = fig.axes[0]
    counts = [t.get_text() for t in ax.texts if "/" in t.get_text()]
    assert sorted(counts) == sorted(["1/7", "3/7", "6/7", "0/7", "0/7", "0/7"])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(label.startswith("body.mass = 2") and "not fitted" in label for label in labels)
    assert any(label.startswith("body.mass = 1") for label in labels)
    assert points_under_legend(ax) == 0


# ------------------------------------------------------------------ model.png


def _labels_clear(ax, skip=()) -> tuple[list[str], list, list]:
    """The axes' labels, the pairs of them that overlap and those that cross a drawn line."""
    from test_plots import _boxes_overlap, _drawn, _line_points

    renderer = _drawn(ax.figure)
    texts = [t for t in ax.texts if t.get_text() and not t.get_text().startswith(skip)]
    names = [t.get_text() for t in texts]
    boxes = [t.get_window_extent(renderer) for t in texts]
    clashes = [(names[i], names[j]) for i in range(len(boxes)) for j in range(i) if _boxes_overlap(boxes[i], boxes[j])]
    points = _line_points(ax)
    crossed = [n for n, b in zip(names, boxes)
               if np.any((points[:, 0] > b.x0 + 1) & (points[:, 0] < b.x1 - 1) & (points[:, 1] > b.y0 + 1)
                         & (points[:, 1] < b.y1 - 1))]
    return names, clashes, crossed


def test_the_plane_model_draws_and_names_its_points_of_interest(tmp_path):
    import shutil
    import tomllib

    import rbhyst
    from conftest import DECKS, write_deck
    from rbhyst.report.run import plot_body

    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    d["analysis"].update(duration=0.05, estimate_error=False)
    d["output"] = {"points": [{"name": "top", "point": [-0.1286, 1.0571]}, {"name": "near", "point": [0.02, 0.75]}]}
    res = rbhyst.run(write_deck(tmp_path, d))
    ax = plot_body(res, tmp_path / "model.png").axes[0]
    for name, x in res.layout.points:  # a marker at each point (about G), named
        assert any(np.allclose(np.column_stack([line.get_xdata(), line.get_ydata()]), [x[:2]]) for line in ax.lines)
    names, clashes, crossed = _labels_clear(ax, skip=("part",))
    assert {"top", "near", "G"} <= set(names) and not clashes and not crossed


def test_the_space_model_s_isometric_view_is_large_and_its_labels_clear(tmp_path):
    import shutil
    import tomllib

    import rbhyst
    from conftest import DECKS, write_deck
    from rbhyst.report.model3d import plot_body_3d

    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = tomllib.loads((DECKS / "cabinet_3d.toml").read_text())
    d["analysis"].update(duration=0.05, estimate_error=False)
    res = rbhyst.run(write_deck(tmp_path, d))
    fig = plot_body_3d(res, tmp_path / "model.png")
    iso = next(ax for ax in fig.axes if ax.get_title() == "isometric")
    area = {ax.get_title(): ax.get_position().width * ax.get_position().height for ax in fig.axes}
    assert all(area["isometric"] >= 2.5 * a for t, a in area.items() if t != "isometric")
    names, clashes, crossed = _labels_clear(iso)
    n = sum(el.count for el in res.system.elements)
    assert {f"e{k}" for k in range(1, n + 1)} | {"G", "x1", "x2", "x3"} <= set(names)
    assert not clashes and not crossed
    assert overlapping_titles(fig) == []


def test_every_figure_of_a_run_reads_in_print(tmp_path):
    """Printed from report.html on A4 (shrunk to the page's width and height, or at its pixels'
    size), no text of a run's figures is below 7.9 pt (the spectra's and loops' were 4.7 and 4.9)."""
    import shutil
    import tomllib

    import rbhyst
    from conftest import DECKS, write_deck
    from rbhyst.report import run as figures
    from rbhyst.report.spectra import plot_spectra

    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = tomllib.loads((DECKS / "seed_wri.toml").read_text())
    d["analysis"].update(duration=1.0, estimate_error=False)
    d["elements"][0]["stroke"] = 0.004
    d["output"] = {"points": [{"name": "top", "point": [-0.1286, 1.0571]}], "spectra": {"damping": [0.02, 0.05]}}
    res = rbhyst.run(write_deck(tmp_path, d))
    made = {"model": figures.plot_body(res, tmp_path / "m.png"),
            "support": figures.plot_excitation(res, tmp_path / "s.png"),
            "x1": figures.plot_response(res, 0, tmp_path / "x.png"),
            "point": figures.plot_point(res, "top", tmp_path / "p.png"),
            "loops": figures.plot_element_loops(res, tmp_path / "l.png"),
            "energy": figures.plot_energy(res, tmp_path / "e.png"),
            "spectra": plot_spectra(res.spectra, tmp_path / "sp.png", title="seed")}
    small = {k: round(smallest_print_pt(f), 2) for k, f in made.items() if smallest_print_pt(f) < 7.9}
    assert small == {}


def ida_cases(n_values: int) -> list[dict]:
    """Cases of 3 motions x 4 levels x n_values masses, their peaks rising with level and mass."""
    out = []
    for m in range(3):
        for s in (0.5, 1.0, 1.5, 2.0):
            for k in range(n_values):
                out.append({"motion": f"m{m}", "scale": s, "status": "ok", "vary": {"body.mass": str(100.0 + 5 * k)},
                            "peaks": {"peak_u1_m": 0.01 * s * (1 + k / 48) * (1 + 0.1 * m),
                                      "peak_at1_m_s2": 3 * s * (1 - k / 96)}})
    return out


@pytest.mark.parametrize("n_values", [3, 48])
def test_ida_tells_its_combinations_within_the_figure(tmp_path, n_values):
    """A few values a legend, many (48 masses: a legend running off the figure) a colour bar with
    at most MAX_ENTRIES labels; every text inside the figure."""
    from rbhyst.report.sweep import MAX_ENTRIES, plot_ida

    fig = plot_ida(ida_cases(n_values), ["peak_u1_m", "peak_at1_m_s2"], ["body.mass"], "scale factor",
                   tmp_path / "ida.png", {"body.mass": "kg"})
    r = drawn(fig).canvas.get_renderer()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    if n_values <= MAX_ENTRIES:
        assert len(legends) == 1 and len(legends[0].get_texts()) > n_values
    else:
        assert not legends
        bar = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
        assert len(bar) == 1 and 2 <= len(bar[0].get_yticklabels()) <= MAX_ENTRIES
    box = fig.bbox
    for t in fig.findobj(Text):
        if t.get_visible() and t.get_text().strip():
            e = t.get_window_extent(r)
            assert box.x0 - 1 <= e.x0 and e.x1 <= box.x1 + 1 and box.y0 - 1 <= e.y0 and e.y1 <= box.y1 + 1, t.get_text()


def test_an_mss_isolator_is_drawn_by_its_shear_lines(tmp_path):
    """element_loops.png draws an isolator with coupled shear by its two shear lines (their columns'
    resultant against deformation), not by its n springs: the box's 4 isolators x (axial + 8
    springs) = 36 elements make 4 x 3 panels."""
    from conftest import write_deck
    from test_mss import _box

    import rbhyst
    from rbhyst.report.run import loop_panels, plot_element_loops

    res = rbhyst.run(write_deck(tmp_path, _box("mss", 30.0)), estimate=False)
    panels = loop_panels(res)
    assert len(res.system.elements) == 36 and len(panels) == 12
    shear = [p for p in panels if " shear " in p[0]]
    assert [p[1] for p in shear[:2]] == ["iso1_shear1_u_m", "iso1_shear2_u_m"]
    fig = plot_element_loops(res, tmp_path / "loops.png")
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 12
    assert overlapping_titles(fig) == []
