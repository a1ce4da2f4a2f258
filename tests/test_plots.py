"""What the figures show, read from their artists (never from pixels): the measured loop above
the fit, plain tick labels, no panel of numerical noise, the Nyquist frequency of a record,
legends for what is marked, lines that do not hide each other, units on every axis."""

from __future__ import annotations

import numpy as np
import pytest

from rbhyst.analyses.calibration import loop_result
from rbhyst.model.deck import key_unit
from rbhyst.model.hysteresis import parameter_set


def _line(ax, label):
    found = [ln for ln in ax.get_lines() if ln.get_label() == label]
    assert len(found) == 1, [ln.get_label() for ln in ax.get_lines()]
    return found[0]


# ---------------------------------------------------------------- loops.png


def test_measured_loop_is_drawn_over_the_fit_as_a_line_with_markers(tmp_path):
    from rbhyst.report.loops import plot_loops

    p = parameter_set({"kb": 2e5, "f0": 1e3, "alpha": 700.0}, {"kb": 2e5, "f0": 1e3, "alpha": 700.0})
    u = 0.01 * np.sin(np.linspace(0.0, 4 * np.pi, 2001))
    clean = loop_result("s", p, u).f
    res = loop_result("s", p, u, clean + np.random.default_rng(1).normal(0.0, 20.0, u.size))
    fig = plot_loops([res], tmp_path / "loops.png", initial={"s": p})
    ax = fig.axes[0]
    data, fit = _line(ax, "test data"), _line(ax, "VRM fit")
    assert data.get_zorder() > fit.get_zorder()
    # markers on a thin line through every point: loops, not a cloud of 300 markers
    assert data.get_marker() not in (None, "None", "", " ") and data.get_linestyle() not in ("None", "", " ")
    assert data.get_linewidth() < fit.get_linewidth()
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


# ---------------------------------------------------------------- spectra.png


def _pulse_along_x2(tmp_path):
    import rbhyst
    from conftest import square_linear_deck, write_deck

    d = square_linear_deck()
    d["elements"][2]["point"] = [0.5, 0.1]  # not quite symmetric: rounding reaches x1
    d["excitation"] = {"support": {"x2": {"type": "half-sine", "amplitude": 10.0, "units": "g",
                                          "duration": 0.011}}}
    d["analysis"].update(dt=0.0005, duration=0.5, estimate_error=False)
    d["output"] = {"points": [{"name": "top", "point": [0.3, 0.5]}],
                   "spectra": {"damping": [0.05], "periods_s": [0.01, 0.03, 0.1, 0.3]}}
    return rbhyst.run(write_deck(tmp_path, d)).spectra


def test_a_direction_of_rounding_gets_no_panel_but_a_plain_line(tmp_path):
    from rbhyst.report.spectra import NEGLIGIBLE, plot_spectra, shown_directions

    spectra = _pulse_along_x2(tmp_path)
    x1 = max(float(spectra.sa(loc, "x1").max()) for loc in ("G", "top"))
    x2 = max(float(spectra.sa(loc, "x2").max()) for loc in ("ground", "G", "top"))
    assert x1 < NEGLIGIBLE * x2 and x2 > 50.0  # the scene: a 10 g pulse, nothing across it
    assert shown_directions(spectra) == (["x2"], {"x1": x1})
    fig = plot_spectra(spectra, tmp_path / "spectra.png", title="pulse")
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles == ["along x2"]
    assert "no response along x1" in fig._suptitle.get_text().replace("\n", " ")
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert not [t for t in legend if "Nyquist" in t]  # an analytic pulse has no sample step


def test_both_directions_of_a_real_response_keep_their_panels(tmp_path):
    from rbhyst.report.spectra import shown_directions
    from rbhyst.solve.located import LocatedSpectra
    from rbhyst.solve.spectra import Spectrum

    spectra = _pulse_along_x2(tmp_path)
    s = spectra.spectrum
    sa = s.sa.copy()
    sa[:, :, [spectra.index(loc, "x1") for loc in ("G", "top")]] = 1e-6 * sa.max()  # small but real
    moved = LocatedSpectra(spectra.signals, Spectrum(periods=s.periods, dampings=s.dampings, dt=s.dt,
                                                     samples=s.samples, sd=s.sd, sa=sa))
    assert shown_directions(moved) == (["x2", "x1"], {})


def test_the_nyquist_frequency_of_a_record_is_marked(tmp_path):
    from conftest import DECKS
    from rbhyst.report.spectra import plot_spectra
    from rbhyst.analyses.record_spectrum import record_spectrum

    spectra = record_spectrum(DECKS / "records" / "synthetic_x1.csv", "g")  # 0.01 s samples
    assert spectra.nyquist_hz() == pytest.approx(50.0) and spectra.nyquist_hz("x1") == pytest.approx(50.0)
    fig = plot_spectra(spectra, tmp_path / "spectra.png")
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert [t for t in legend if "Nyquist" in t and "50 Hz" in t], legend


def test_a_runs_ground_records_carry_their_sample_step(tmp_path):
    import shutil

    import rbhyst
    from conftest import DECKS, seed_deck, write_deck

    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = seed_deck(duration=0.3, estimate_error=False)
    d["excitation"]["support"]["x1"] = {"file": "records/synthetic_x1.csv", "units": "g"}  # x2 stays a sine
    d["output"] = {"spectra": {"periods_s": [0.01, 0.1]}}
    spectra = rbhyst.run(write_deck(tmp_path, d)).spectra
    assert spectra.record_dt == (("x1", 0.01),)
    assert spectra.nyquist_hz("x1") == pytest.approx(50.0)
    assert spectra.nyquist_hz("x2") == pytest.approx(50.0)  # the body feels the x1 record there too


# ---------------------------------------------------------------- element_loops.png, model.png, energy.png


def _drawn(fig):
    """The figure drawn under rbhyst's style, and its renderer (text extents in pixels)."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from rbhyst.report._style import STYLE

    with matplotlib.rc_context(STYLE):
        FigureCanvasAgg(fig)
        fig.canvas.draw()
    return fig.canvas.get_renderer()


def _x_tick_gaps(ax, renderer) -> list[float]:
    lo, hi = sorted(ax.get_xlim())
    shown = [t for t, x in zip(ax.get_xticklabels(), ax.get_xticks()) if lo <= x <= hi and t.get_text()]
    boxes = sorted((t.get_window_extent(renderer) for t in shown), key=lambda b: b.x0)
    return [b.x0 - a.x1 for a, b in zip(boxes, boxes[1:])]


@pytest.fixture(scope="module")
def machine():
    import rbhyst
    from conftest import DECKS

    return rbhyst.run(DECKS / "machine_on_mounts.toml")


def test_element_loop_tick_labels_keep_apart(machine, tmp_path):
    """The machine's mount e3 moves 0.1 mm: six labels -0.10 ... 0.15 ran together."""
    from rbhyst.report.run import plot_element_loops

    fig = plot_element_loops(machine, tmp_path / "element_loops.png")
    renderer = _drawn(fig)
    em = renderer.points_to_pixels(9.0)
    for ax in fig.axes:
        if ax.get_visible():
            gaps = _x_tick_gaps(ax, renderer)
            assert gaps and min(gaps) >= em, (ax.get_title(), gaps)


def test_stroke_limits_have_a_legend(tmp_path):
    import rbhyst
    from conftest import seed_deck, write_deck
    from rbhyst.report.run import plot_element_loops

    d = seed_deck(duration=0.2, estimate_error=False)
    d["elements"][0]["stroke"] = [-0.01, 0.015]
    res = rbhyst.run(write_deck(tmp_path, d))
    fig = plot_element_loops(res, tmp_path / "element_loops.png")
    first, second = fig.axes[:2]
    # (0.2 s of the seed's record bends the element a fraction of a millimetre: the limits are off its axis)
    assert [t.get_text() for t in first.get_legend().get_texts()] == ["stroke limits -10, +15 mm,\nbeyond the axis"]
    assert second.get_legend() is None  # no stroke, nothing to explain


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def _line_points(ax, step: float = 1.0):
    """Points every ``step`` pixels along every line drawn on ``ax`` (outline, elements, dampers)."""
    out = []
    for ln in ax.get_lines():
        px = ax.transData.transform(ln.get_xydata())
        for a, b in zip(px[:-1], px[1:]):
            n = max(2, int(np.hypot(*(b - a)) / step) + 1)
            out.append(a + (b - a) * np.linspace(0.0, 1.0, n)[:, None])
    return np.vstack(out)


CABINET_DAMPERS = [{"part": 1, "vertex": 1, "angle_deg": 270.0, "c": 800.0, "count": 2},
                   {"part": 1, "vertex": 2, "angle_deg": 0.0, "c": 800.0},
                   {"part": 1, "vertex": 4, "angle_deg": 200.0, "c": 800.0}]
SEED_DAMPERS = [{"vertex": 1, "angle_deg": 0.0, "c": 800.0}, {"vertex": 2, "angle_deg": 90.0, "c": 800.0, "count": 2},
                {"vertex": 3, "angle_deg": 45.0, "c": 300.0}, {"point": [0.0, 0.0], "angle_deg": 30.0, "c": 100.0}]


@pytest.mark.parametrize("deck, dampers", [("cabinet_transformer.toml", CABINET_DAMPERS),
                                           ("seed_wri.toml", SEED_DAMPERS)], ids=["cabinet", "seed"])
def test_model_labels_cover_no_other_label_nor_a_line(tmp_path, deck, dampers):
    """Dampers at the elements' corners, along their lines and across them: every label clear of
    the others and of every line drawn (the body's outline, the elements, the dampers)."""
    import shutil
    import tomllib

    import rbhyst
    from conftest import DECKS, write_deck
    from rbhyst.report.run import plot_body

    shutil.copytree(DECKS / "records", tmp_path / "records")
    d = tomllib.loads((DECKS / deck).read_text())
    d["analysis"].update(duration=0.05, estimate_error=False)
    d["dampers"] = dampers
    fig = plot_body(rbhyst.run(write_deck(tmp_path, d)), tmp_path / "model.png")
    renderer = _drawn(fig)
    ax = fig.axes[0]
    texts = [t for t in ax.texts if t.get_text() and not t.get_text().startswith("part")]
    names = [t.get_text() for t in texts]
    assert len([n for n in names if n.startswith("d")]) == len(dampers) and len(names) == len(set(names))
    boxes = [t.get_window_extent(renderer) for t in texts]
    clashes = [(names[i], names[j]) for i in range(len(boxes)) for j in range(i) if _boxes_overlap(boxes[i], boxes[j])]
    assert not clashes
    points = _line_points(ax)
    crossed = [n for n, b in zip(names, boxes)
               if np.any((points[:, 0] > b.x0 + 1) & (points[:, 0] < b.x1 - 1) & (points[:, 1] > b.y0 + 1)
                         & (points[:, 1] < b.y1 - 1))]
    assert not crossed


def test_input_energy_shows_under_the_hysteretic(machine, tmp_path):
    from rbhyst.report.run import plot_energy

    fig = plot_energy(machine, tmp_path / "energy.png")
    ax = fig.axes[0]
    given, hysteretic = _line(ax, "input"), _line(ax, "hysteretic\n(dissipated + stored)")
    assert given.get_linewidth() >= 2.5 * hysteretic.get_linewidth()  # a band a dashed line runs in
    assert hysteretic.get_zorder() > given.get_zorder()
    assert hysteretic.get_linestyle() != given.get_linestyle()
    assert given.get_alpha() is not None and given.get_alpha() < 1.0


# ---------------------------------------------------------------- the units of deck keys


def _numeric_keys(node, key=""):
    """Dotted keys (list items from 1) of every number or list of numbers in a deck mapping."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _numeric_keys(v, f"{key}.{k}" if key else k)
    elif isinstance(node, list) and node and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in node):
        yield key
    elif isinstance(node, list):
        for i, v in enumerate(node, start=1):
            yield from _numeric_keys(v, f"{key}[{i}]")
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield key


def test_every_number_of_a_deck_has_a_unit():
    import tomllib

    from conftest import DECKS, seed_deck
    from rbhyst.model.deck import parse_deck

    decks = [tomllib.loads(p.read_text()) for p in sorted(DECKS.glob("*.toml"))]
    pulse = seed_deck()
    pulse["excitation"]["support"]["x2"] = {"type": "half-sine", "amplitude": 5.0, "units": "m/s2",
                                            "duration": 0.01, "start": 0.1}
    pulse["excitation"]["support"]["x1"].update(ramp_cycles=2.0, cycles=8.0, start=0.0)
    pulse["body"] = {"mass": 500.0, "mass_centre": [0.1, 0.2], "inertia": 80.0, "gravity": [0.0, -9.81],
                     "vertices": [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]}
    pulse["elements"][0]["stroke"] = [-0.01, 0.02]
    pulse["dampers"] = [{"point": [0.0, 0.0], "angle_deg": 10.0, "c": 5.0, "count": 2}]
    pulse["damping"] = {"rayleigh": {"ratio": [0.02, 0.03], "frequencies_hz": [2.0, 8.0]}}
    pulse["output"] = {"every": 2, "points": [{"name": "a", "point": [0.0, 1.0]}],
                       "spectra": {"damping": [0.05], "periods_s": [0.1]}}
    decks.append(pulse)
    missing = set()
    for data in decks:
        deck = parse_deck(data).model_dump(mode="python", exclude_none=True)
        for key in _numeric_keys(deck):
            if key_unit(key, deck) is None:
                missing.add(key)
    assert not missing


def test_units_of_keys():
    data = {"excitation": {"support": {"x1": {"type": "sine", "amplitude": 0.3, "units": "m/s2"}},
                           "force": {"m3": {"file": "m.csv", "units": "kN m"}}}}
    assert [key_unit(k, data) for k in (
        "body.mass", "body.parts[2].mass", "hysteresis.wri_shear.loading.kb", "hysteresis.s.unloading.alpha",
        "elements[2].count", "elements.1.stroke", "dampers[1].c", "excitation.support.x1.amplitude",
        "excitation.force.m3.scale", "analysis.duration", "elements[1].hysteresis", "title")] == [
        "kg", "kg", "N/m", "1/m", "", "m", "N s/m", "m/s²", "", "s", None, None]


# ---------------------------------------------------------------- ida.png, vary.png


def _sweep_table(masses, kbs, levels=(0.5, 1.0, 1.5), motions=("a", "b")):
    """A cases table as rbhyst sweep writes it: peaks that grow with the level and the mass."""
    header = ["case", "motion", "scale", "body.mass", "hysteresis.s.loading.kb", "status", "message",
              "peak_u1_m", "peak_u2_m", "peak_theta3_rad", "peak_at1_m_s2", "peak_at2_m_s2", "peak_e1_f_N"]
    rows, n = [], 0
    for i, m in enumerate(motions):
        for s in levels:
            for mass in masses:
                for kb in kbs:
                    n += 1
                    u = 1e-3 * s * (1 + i / 10) * mass / 800 * 2e5 / kb
                    rows.append([n, m, s, repr(mass), repr(kb), "ok", "", u, 0.5 * u, 1e-4 * s, 3.0 * s, 2.0 * s,
                                 100.0 * s])
    return header, rows


UNITS = {"body.mass": "kg", "hysteresis.s.loading.kb": "N/m"}


def test_ida_tells_nine_combinations_apart_by_colour_and_line_style(tmp_path):
    from rbhyst.report.sweep import _records, plot_ida, write_plots

    header, rows = _sweep_table([700.0, 815.773, 900.0], [2e5, 2.2e5, 2.4e5])
    assert write_plots(header, rows, list(UNITS), "factors", tmp_path, UNITS) == ["ida.png", "vary.png"]
    ok = _records(header, rows, list(UNITS))
    fig = plot_ida(ok, ["peak_u1_m", "peak_at1_m_s2"], list(UNITS), "scale factor", tmp_path / "ida.png", UNITS)
    panel, cell = fig.axes[0], fig.axes[2]
    styles = {(ln.get_color(), ln.get_linestyle()) for ln in panel.get_lines()}
    assert len(panel.get_lines()) == 9 and len(styles) == 9  # every combination, each its own look
    legend = [t.get_text() for t in cell.get_legend().get_texts()]
    assert legend == ["body.mass [kg]:", "  700", "  815.773", "  900", "hysteresis.s.loading.kb [N/m]:",
                      "  200000", "  220000", "  240000", "(median over the motions)"]
    assert "84th percentiles in stats.csv" in fig._suptitle.get_text()


def test_ida_of_one_combination_shows_each_motion_median_and_84th(tmp_path):
    from rbhyst.report.sweep import _records, plot_ida

    header, rows = _sweep_table([800.0], [2e5])
    fig = plot_ida(_records(header, rows, []), ["peak_u1_m"], [], "scale factor", tmp_path / "ida.png")
    assert [t.get_text() for t in fig.axes[1].get_legend().get_texts()] == [
        "each motion", "median over the motions", "84th percentile"]
    assert len(fig.axes[0].get_lines()) == 2 + 2  # two motions, the median, the 84th percentile


def test_vary_shows_displacements_and_accelerations_against_keys_with_units(tmp_path):
    from rbhyst.report.sweep import VARY_PEAKS, _records, plot_vary

    header, rows = _sweep_table([700.0, 900.0], [2e5, 2.4e5])
    fig = plot_vary(_records(header, rows, list(UNITS)), list(VARY_PEAKS), list(UNITS), "scale factor",
                    tmp_path / "vary.png", UNITS)
    assert [ax.get_ylabel() for ax in fig.axes[:4]] == ["peak |u1| [m]", "peak |u2| [m]", "peak |at1| [m/s²]",
                                                        "peak |at2| [m/s²]"]
    assert {ax.get_xlabel() for ax in fig.axes} == {"body.mass [kg]", "hysteresis.s.loading.kb [N/m]"}


def test_a_sweeps_keys_get_their_units_from_its_deck(tmp_path):
    import tomli_w

    from conftest import seed_deck, write_deck
    from rbhyst.analyses.sweep import load_sweep
    from rbhyst.analyses.sweep.runner import _vary_units

    write_deck(tmp_path, seed_deck(duration=0.1), name="base")
    (tmp_path / "sweep.toml").write_text(tomli_w.dumps({
        "deck": "base.toml",
        "motions": [{"name": "s", "x1": {"type": "sine", "amplitude": 0.3, "frequency_hz": 2.0, "units": "g"}}],
        "vary": {"body.mass": [700.0, 800.0], "excitation.support.x1.amplitude": [0.1, 0.2],
                 "elements[1].count": [1, 2]}}))
    assert _vary_units(load_sweep(tmp_path / "sweep.toml")) == {
        "body.mass": "kg", "excitation.support.x1.amplitude": "g", "elements[1].count": ""}


# ---------------------------------------------------------------- the console's elements


def test_run_prints_one_row_per_element_with_summary_numbers(tmp_path):
    import json

    from conftest import invoke, seed_deck, write_deck

    d = seed_deck(duration=0.5, estimate_error=False)
    d["elements"][0]["stroke"] = [-0.01, 0.015]
    d["elements"][3]["stroke"] = 0.002
    code, err = invoke("run", write_deck(tmp_path, d), "--out", tmp_path / "out", "--no-plots")
    assert code == 0, err
    lines = err.splitlines()
    assert lines[-1] == f"wrote {tmp_path / 'out'}" and lines[-8].startswith("chang, dt = 0.001 s")
    assert lines[-7] == "elements (peaks over the run):"
    assert lines[-6].split() == ["element", "set", "angle", "[deg]", "peak", "|f|", "[kN]", "peak", "u", "[mm]",
                                 "stroke", "[mm]", "used"]
    assert len({len(line) for line in lines[-6:-1]}) <= 2  # aligned (the last column may be shorter)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    table = [line.replace("(each)", "").split() for line in lines[-5:-1]]
    assert [r[0] for r in table] == ["e1-e2", "e3-e4", "e5-e6", "e7-e8"]  # one row per [[elements]] entry
    for k, (row, el) in enumerate(zip(table, summary["elements"])):
        first = 1 + 2 * k
        assert row[1] == el["hysteresis"] and float(row[2]) == el["angle_deg"]
        assert float(row[3]) == pytest.approx(summary["peaks"][f"e{first}_f_N"] / 1e3, rel=1e-3)
        u = summary["extremes"][f"e{first}_u_m"]
        expect = el["stroke"]["peak_deformation_m"] if "stroke" in el else max(u["max"], u["min"], key=abs)
        assert float(row[4]) == pytest.approx(expect * 1e3, rel=1e-3)
        if "stroke" in el:
            lo, hi = el["stroke"]["limits_m"]
            assert row[5:7] == [f"{lo * 1e3:g},", f"+{hi * 1e3:g}"]
            assert float(row[7].rstrip("%")) == pytest.approx(100 * el["stroke"]["utilization"], rel=0.05)
        else:
            assert row[5:] == ["-", "-"]


def test_many_elements_show_the_most_loaded_and_say_how_many_more():
    from rbhyst.report.console import element_table

    n = 20
    used = [0.25 * (k % 7) for k in range(n)]  # up to 150 %
    summary = {"elements": [{"hysteresis": "s", "angle_deg": 0.0, "count": 1,
                             "stroke": {"limits_m": [-0.01, 0.01], "peak_deformation_m": 0.01 * u, "utilization": u}}
                            for u in used],
               "peaks": {f"e{k + 1}_f_N": 100.0 + k for k in range(n)},
               "extremes": {f"e{k + 1}_u_m": {"max": 0.01 * u, "min": 0.0} for k, u in enumerate(used)}}
    lines = element_table(summary)
    assert lines[0] == "elements: the 8 most loaded of 20 (stroke used, then peak force):"
    assert lines[-1] == "  ... and 12 more (every element in summary.json)"
    rows = [line.split() for line in lines[2:-1]]
    assert len(rows) == 8 and [r[0] for r in rows] == ["e14", "e7", "e20", "e13", "e6", "e19", "e12", "e5"]
    assert [r[-1] for r in rows] == ["over"] * 5 + ["100%"] * 3 and rows[0][-2] == "150%"
    assert len({line.index("%") for line in lines[2:-1]}) == 1  # the percentages aligned


def test_no_stroke_no_stroke_columns():
    from rbhyst.report.console import element_table

    summary = {"elements": [{"hysteresis": "m", "angle_deg": 45.0, "count": 1}],
               "peaks": {"e1_f_N": 602.2}, "extremes": {"e1_u_m": {"max": 0.001, "min": -0.007011}}}
    assert element_table(summary) == ["elements (peaks over the run):",
                                      "  element  set  angle [deg]  peak |f| [N]  peak u [mm]",
                                      "  e1       m             45         602.2       -7.011"]


def test_an_element_at_rest_gets_no_panel_of_rounding_noise(tmp_path):
    """A pulse along x2 on a symmetric body leaves the x1 elements at 1e-13 N: their panels say
    so instead of drawing noise as if it were a loop."""
    import rbhyst
    from conftest import write_deck
    from test_accelerations import pulse_deck
    from rbhyst.report.run import plot_element_loops

    res = rbhyst.run(write_deck(tmp_path, pulse_deck("half-sine")), estimate=False)
    fig = plot_element_loops(res, tmp_path / "loops.png")
    axes = [ax for ax in fig.axes if ax.get_visible()]
    drawn = [bool(ax.lines) for ax in axes]
    said = [" ".join(t.get_text() for t in ax.texts) for ax in axes]
    assert drawn == [True, True, False, False]
    assert all(s.startswith("at rest: |f| at most ") for s in said[2:])


def test_a_response_of_rounding_is_said_to_be_at_rest(tmp_path):
    """A symmetric square shaken along x1: theta3 and u2 stay at rounding (1e-18 m, 1e-39 rad);
    their panels say so rather than draw the noise as a response, and keep the run's time axis;
    u1's is drawn."""
    import rbhyst
    from conftest import square_linear_deck, write_deck
    from rbhyst.report.run import plot_response

    data = square_linear_deck()
    data["excitation"] = {"support": {"x1": {"type": "sine", "amplitude": 0.2, "frequency_hz": 2.0, "units": "g",
                                             "cycles": 3}}}
    data["analysis"] = {"dt": 0.002, "duration": 2.0}
    res = rbhyst.run(write_deck(tmp_path, data), estimate=False)
    for k, drawn in ((0, True), (1, False), (2, False)):
        fig = plot_response(res, k, tmp_path / f"r{k}.png")
        for ax in fig.axes:
            visible = [line for line in ax.lines if line.get_alpha() != 0.0]
            said = " ".join(t.get_text() for t in ax.texts)
            assert bool(visible) == drawn and said.startswith("at rest: ") != drawn, (k, said)
            assert ax.get_xlim()[1] >= 1.9  # (the run's 2 s, not matplotlib's empty 0-1)


def test_ida_medians_are_each_combinations_own():
    """plot_ida's medians and 84th percentiles, taken a matrix of equal-sized sets at a time,
    equal numpy's of each combination's set at each level alone, to the bit: sets of 1-4
    motions, a level where no motion has the peak (nan), a peak some motions lack."""
    import random

    from rbhyst.analyses.sweep.tables import PERCENTILE
    from rbhyst.report.sweep import _groups, _medians

    rng = random.Random(3)
    cases = []
    for k in range(40):
        for s in (0.5, 1.0, 1.5):
            for m in range(rng.randint(1, 4)):
                peaks = {} if (k == 7 and s == 1.0) or rng.random() < 0.1 else {"peak_u1_m": rng.random()}
                cases.append({"motion": f"m{m}", "scale": s, "status": "ok", "vary": {"body.mass": str(k)},
                              "peaks": peaks})
    groups = _groups(cases, ["body.mass"])
    idents = sorted(groups)
    for with_p84 in (True, False):
        got = dict(_medians(groups, idents, "peak_u1_m", with_p84))
        for ident in idents:
            levels, med, p84 = got[ident]
            assert levels == [0.5, 1.0, 1.5]
            for s, m, p in zip(levels, med, p84 or [None] * 3):
                x = np.array([c["peaks"]["peak_u1_m"] for c in groups[ident]
                              if c["scale"] == s and "peak_u1_m" in c["peaks"]])
                if len(x) == 0:
                    assert np.isnan(m)
                    continue
                assert m == np.median(x)
                if with_p84:
                    assert p == np.percentile(x, PERCENTILE)
    assert np.isnan(dict(_medians(groups, idents, "peak_u1_m", False))[("7",)][1][1])


def test_vary_medians_are_each_values_own():
    """vary.png's median line, its sets of equal size taken a matrix at a time, is numpy's median
    of the peaks at each value alone, to the bit (-0.0 among them)."""
    from rbhyst.report.sweep import _median_at

    rng = np.random.default_rng(0)
    for t in range(200):
        n = int(rng.integers(1, 60))
        x = rng.choice(rng.random(int(rng.integers(1, 10))), n)
        y = rng.random(n)
        y[int(rng.integers(0, n))] = -0.0 if t % 3 == 0 else y[0]
        xs, med = _median_at(x, y)
        assert list(xs) == list(np.unique(x))
        assert [repr(float(np.median(y[x == v]))) for v in xs] == [repr(m) for m in med]
