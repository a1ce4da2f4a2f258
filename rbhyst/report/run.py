"""PNG plots of one analysis, after the seed's Figs. 3-8."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.ticker import MaxNLocator

from rbhyst.solve.result import Result
from rbhyst.report._labels import Labels
from rbhyst.report._style import NEGLIGIBLE, PRINT_WIDTH, TIME_MARGINS, plain_number, save, styled, subplots, write_png


def _draw_outline(ax, v: np.ndarray, fill_alpha: float, labels: list[str], placer: Labels) -> None:
    """The polygon, each vertex labelled outside it, along the bisector of its corner if that
    place is free."""
    closed = np.vstack([v, v[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="0.2", alpha=fill_alpha, lw=0, zorder=1)
    ax.plot(closed[:, 0], closed[:, 1], color="0.2", lw=1.2, zorder=2)
    placer.line(closed)
    n = len(v)
    for i, (label, point) in enumerate(zip(labels, v)):
        into = []  # unit vectors along the two edges that meet here
        for j in (i - 1, (i + 1) % n):
            e = v[j] - point
            into.append(e / (np.linalg.norm(e) or 1.0))
        out = -(into[0] + into[1])
        if np.linalg.norm(out) < 1e-9:  # a straight angle: outward is the normal of the edge
            out = np.array([into[1][1], -into[1][0]])
        placer.add(label, point, out, fontsize=8, color="0.3")


def _shares_line(dp, elements) -> bool:
    """Whether an element acts at the damper's point along the same line (their drawings
    would fall on each other)."""
    return any(math.dist(el.x, dp.x) < 1e-9 and abs(math.sin(math.radians(el.angle_deg - dp.angle_deg))) < 1e-6
               for el in elements)


@styled
def plot_body(result: Result, path: Path):
    """The body (every part, the denser darker, with its mass), its mass centre G, its points of
    interest and its elements (seed Fig. 3a); a damper on an element's line is drawn beside it, in parallel;
    no label covers another (rbhyst.report._labels). Returns the figure (saved to ``path``).

    Long because every mark drawn is registered with one label placer, so that no label covers another.
    """
    system = result.system
    body = system.body
    fig, ax = subplots(figsize=(5.5, 5.5))
    vertex_labels, labels = Labels(), Labels()  # the elements' and dampers' labels first
    fixed = []
    if body.form == "parts":
        # overlapping fills add up: a dense unit inside a shell shows darker
        density = [p.mass / p.area for p in body.parts]
        several = len(body.parts) > 1
        for k, (part, rho) in enumerate(zip(body.parts, density), start=1):
            prefix = f"{k}." if several else "P"
            _draw_outline(ax, part.vertices, 0.08 + 0.3 * rho / max(density),
                          [f"{prefix}{i}" for i in range(1, len(part.vertices) + 1)], vertex_labels)
            c = part.centroid - body.mass_centre
            fixed.append(ax.annotate(f"part {k}\n{part.mass:.4g} kg", c, ha="center", va="center", fontsize=7,
                                     color="0.1", zorder=3))
    else:
        v = body.outlines[0]
        _draw_outline(ax, v, 0.1, [f"P{i}" for i in range(1, len(v) + 1)], vertex_labels)
    ax.plot(0, 0, "k+", ms=10, zorder=3)
    labels.point(0.0, 0.0, 5.0)
    v = np.vstack(body.outlines)
    size = float(np.ptp(v, axis=0).max())
    length = 0.18 * size
    k = 1
    for el in system.elements:
        x, y = el.x
        a = math.radians(el.angle_deg)
        # along its line of action, on the side away from G: clear of the body's outline
        side = 1.0 if x * math.cos(a) + y * math.sin(a) >= 0.0 else -1.0
        ux, uy = side * math.cos(a), side * math.sin(a)
        ex, ey = x + length * ux, y + length * uy
        ax.plot([ex, x], [ey, y], color="C0", lw=2.5, solid_capstyle="round", zorder=4)
        ax.plot(ex, ey, marker="s", color="C0", ms=5, zorder=4)
        labels.line([[x, y], [ex, ey]])
        labels.point(ex, ey, 2.5)
        label = f"e{k}" if el.count == 1 else f"e{k}-{k + el.count - 1}"
        labels.add(label, (ex, ey), (ux, uy), 4.5, fontsize=7, color="C0")  # beyond its free end
        k += el.count
    for k, dp in enumerate(system.dampers, start=1):
        x, y = dp.x
        a = math.radians(dp.angle_deg)
        side = 1.0 if x * math.cos(a) + y * math.sin(a) >= 0.0 else -1.0
        ux, uy = side * math.cos(a), side * math.sin(a)
        # on an element's line it is drawn beside it, in parallel, as a spring and a dashpot are
        nx, ny = -uy, ux
        if nx * x + ny * y < 0.0:  # the side away from G
            nx, ny = -nx, -ny
        shift = 0.06 * size if _shares_line(dp, system.elements) else 0.0
        sx, sy = x + shift * nx, y + shift * ny
        ex, ey = sx + 0.8 * length * ux, sy + 0.8 * length * uy
        ax.plot([x, sx, ex], [y, sy, ey], color="C2", lw=1.5, ls="--", zorder=4)
        mid = ((ex + sx) / 2, (ey + sy) / 2)
        ax.plot(*mid, marker="D", color="C2", ms=5, zorder=4)
        labels.line([[x, y], [sx, sy], [ex, ey]])
        labels.point(*mid, 2.5)
        labels.add(f"d{k}" + (f" x{dp.count}" if dp.count > 1 else ""), mid, (nx, ny), 4.5, fontsize=7,
                   color="C2")  # off its side, away from the element
    for name, x in result.layout.points:  # the points of interest (about G), as model3d draws them
        ax.plot(x[0], x[1], marker="o", ms=5, mfc="white", mec="C1", mew=1.4, zorder=5)
        labels.point(x[0], x[1], 3.5)
        labels.add(name, (x[0], x[1]), (x[0] or 1.0, x[1] or 1.0), 4.5, fontsize=7.5, color="C1")
    labels.pending += vertex_labels.pending
    labels.lines += vertex_labels.lines
    labels.add("G", (0.0, 0.0), (1.0, -1.0), 6.5, fontsize=9)
    ex = result.system.excitation
    if ex.p1 is not None or ex.p2 is not None or ex.m3 is not None:
        ax.plot(*ex.point, marker="*", color="C3", ms=12, zorder=5)
        labels.point(*ex.point, 6.0)
        labels.add("P (loads)", ex.point, (1.0, 1.0), 6.5, color="C3")
    ax.set_aspect("equal")
    ax.margins(0.15)
    ax.set_xlabel("x1 [m]")
    ax.set_ylabel("x2 [m]")
    title = system.title or "Model"
    area = f"A = {body.parts[0].area:.4g} m², " if body.form == "polygon" else ""
    ax.set_title(f"{title}\n{area}m = {system.mass[0]:.6g} kg, J = {system.mass[2]:.6g} kg m² about G",
                 fontsize=9)
    fig.tight_layout()
    labels.place(fig, ax, fixed)
    write_png(fig, path)
    return fig


def _line(ax, result: Result, name: str, scale: float | None = None, unit: str = "", factor: float = 1.0,
          **kw) -> None:
    """One column against time, drawn through every bucket's extremes: no peak is lost; times
    ``factor`` (1e3: metres drawn in mm, ``unit``). Where its peak stays below NEGLIGIBLE of
    ``scale`` (its family's largest, in the column's own unit) the panel says it is at rest
    instead: a symmetric body's cross response is rounding (1e-17 rad), which a line would show
    as a response."""
    peak = result.extremes.peak(name)
    t, y = result.plot.series(result.columns.index(name))
    y = y * factor if factor != 1.0 else y
    if scale is not None and peak < NEGLIGIBLE * scale:
        said = ("exactly zero" if peak == 0.0 else
                f"at most {peak * factor:.1e} {unit}, below 1e-9 of the largest: rounding")
        at_rest(ax, f"at rest: {said}", time_axis=True)
        ax.plot(t[:1], y[:1] * 0.0, alpha=0.0)  # (the run's time span for the shared axis, drawn by none)
        ax.plot(t[-1:], y[-1:] * 0.0, alpha=0.0)
        return
    ax.plot(t, y, **kw)


def at_rest(ax, text: str, time_axis: bool = False) -> None:
    """A panel that shows no line: what it would have drawn, said. ``time_axis``: the panel shares
    its time axis with the figure's others (its ticks are theirs: kept)."""
    ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=7.5, color="0.35", transform=ax.transAxes)
    ax.set_yticks([])
    if not time_axis:
        ax.set_xticks([])
    for side, spine in ax.spines.items():
        spine.set_visible(time_axis and side == "bottom")


def family_scale(result: Result, family: str) -> dict[str, float]:
    """Each coordinate's column of ``family`` ("d" displacements, "at" total accelerations) and
    the family's largest peak in that column's unit (scales.family_scales: a rotation counted
    at the body's radius of gyration)."""
    from rbhyst.solve.scales import family_scales

    coords = result.system.coordinates
    columns = [c.column(family) for c in coords]
    peaks = np.array([result.extremes.peak(c) for c in columns])
    scales = family_scales(peaks, [c.key(family) for c in coords], [family] * len(coords), result.system)
    return dict(zip(columns, map(float, scales)))


@styled
def plot_excitation(result: Result, path: Path):
    """Support acceleration along each direction that has a signal (seed Fig. 5; x3 where a body
    in space has it; the others named in the title). A motion over less than a fifth of the run
    (a shock pulse) is drawn over its own span, from its signal (exact, not the rows at dt).
    Returns the figure (saved to ``path``)."""
    names = [c for c in result.columns if c.startswith("ag") and c.endswith("_m_s2")]
    signals = {n: getattr(result.system.excitation, n[: -len("_m_s2")], None) for n in names}
    drawn = [n for n in names if signals[n] is not None] or names
    run = result.stats.steps * result.settings.dt  # s
    window = short_motion([signals[n] for n in drawn], run)
    fig, axes = subplots(len(drawn), 1, figsize=(PRINT_WIDTH, 2.25 * len(drawn) if len(drawn) > 1 else 2.8), sharex=True,
                         squeeze=False)
    axes = axes[:, 0]
    for name, ax in zip(drawn, axes):
        if window is None:
            _line(ax, result, name, lw=0.7, color="C0")
        else:
            t = np.linspace(*window, 2001)
            ax.plot(t, signals[name](t), lw=0.9, color="C0")
            ax.set_xlim(*window)
        ax.set_ylabel(f"{name[:-5]} [m/s²]")
    title = "Support acceleration"
    if window is not None:
        title += f" over its {window[1] - window[0]:.3g} s of the run's {run:.3g} s"
    none = [n[2:-5] for n in names if n not in drawn]
    if none:
        title += f" (none along x{', x'.join(none)})"
    axes[0].set_title(title)
    axes[-1].set_xlabel("time [s]")
    save(fig, path, TIME_MARGINS)
    return fig


def short_motion(signals, run: float) -> tuple[float, float] | None:
    """The span to draw a support motion over (s) where every signal is a pulse ending before a
    fifth of the run: the pulses' span and half of it on either side (from 0 at the earliest);
    None for any other motion (drawn over the run)."""
    spans = [(s.start, s.end) for s in signals if s is not None and hasattr(s, "start") and hasattr(s, "duration")]
    if not spans or len(spans) < sum(s is not None for s in signals):
        return None
    t0, t1 = min(a for a, _ in spans), max(b for _, b in spans)
    if t1 >= 0.2 * run:
        return None
    margin = 0.5 * (t1 - t0)
    return max(0.0, t0 - margin), t1 + margin


RESPONSE = (("u1_m", "at1_m_s2", "u1 [mm]", "at1 [m/s²]", "mass centre along x1"),
            ("u2_m", "at2_m_s2", "u2 [mm]", "at2 [m/s²]", "mass centre along x2"),
            ("theta3_rad", "alphat3_rad_s2", "θ3 [mrad]", "θt3'' [rad/s²]", "rotation about x3"))


def response_rows(coordinates) -> list[tuple[str, str, str, str, str]]:
    """(displacement column, total acceleration column, their labels, what the coordinate is) of
    each coordinate of q: RESPONSE for the plane body."""
    out = []
    for c in coordinates:
        if c.rotation:
            out.append((c.column("d"), c.column("at"), f"θ{c.axis} [mrad]", f"θt{c.axis}'' [rad/s²]",
                        f"rotation about x{c.axis}"))
        else:
            out.append((c.column("d"), c.column("at"), f"u{c.axis} [mm]", f"at{c.axis} [m/s²]",
                        f"mass centre along x{c.axis}"))
    return out


#: displacements (m, rad) are drawn in mm and mrad: a mount's millimetres read as they are,
#: not as 0.002 under a "1e-3" above the axis
SHOWN_IN_MILLI = 1e3


def response_files(coordinates) -> list[str]:
    """response_x1.png, ..., response_theta3.png: one per coordinate of q."""
    return [f"response_{'theta' if c.rotation else 'x'}{c.axis}.png" for c in coordinates]


@styled
def plot_response(result: Result, k: int, path: Path):
    """Relative displacement and total acceleration of coordinate k (seed Figs. 6-8), a panel of
    rounding said to be at rest. Returns the figure (saved to ``path``)."""
    rows = response_rows(result.system.coordinates)
    d, at, d_label, at_label, name = rows[k]
    d_scale, at_scale = family_scale(result, "d")[d], family_scale(result, "at")[at]
    fig, axes = subplots(2, 1, figsize=(PRINT_WIDTH, 4.5), sharex=True)
    _line(axes[0], result, d, d_scale, d_label.split("[")[1].rstrip("]"), SHOWN_IN_MILLI, lw=0.8, color="C0")
    axes[0].set_ylabel(d_label)
    axes[0].set_title(f"Relative displacement and total acceleration: {name}")
    _line(axes[1], result, at, at_scale, at_label.split("[")[1].rstrip("]"), lw=0.6, color="C1")
    axes[1].set_ylabel(at_label)
    axes[1].set_xlabel("time [s]")
    save(fig, path, TIME_MARGINS)
    return fig


@styled
def plot_point(result: Result, name: str, path: Path):
    """Relative displacement and total acceleration of a point of interest along x1 and x2 (and x3
    in space). Returns the figure (saved to ``path``)."""
    x = dict(result.layout.points)[name] + result.system.body.mass_centre
    axes_of = [c.axis for c in result.system.coordinates if not c.rotation]
    rows = ([(f"{name}_u{k}_m", f"u{k} [mm]", "C0") for k in axes_of]
            + [(f"{name}_at{k}_m_s2", f"at{k} [m/s²]", "C1") for k in axes_of])
    fig, axes = subplots(len(rows), 1, figsize=(PRINT_WIDTH, 1.75 * len(rows)), sharex=True)
    tops = {kind: max(result.extremes.peak(c) for c, _, _ in rows if f"_{kind}" in c) for kind in ("u", "at")}
    for ax, (column, label, colour) in zip(axes, rows):
        _line(ax, result, column, tops["at" if "_at" in column else "u"], label.split("[")[1].rstrip("]"),
              1.0 if "_at" in column else SHOWN_IN_MILLI, lw=0.7, color=colour)
        ax.set_ylabel(label)
    axes[0].set_title(f"Relative displacement and total acceleration: point {name} "
                      f"({', '.join(f'{c:.4g}' for c in x)}) m")
    axes[-1].set_xlabel("time [s]")
    save(fig, path, TIME_MARGINS)
    return fig


def loop_panels(result: Result) -> list[tuple[str, str, str, tuple | None, tuple | None]]:
    """What element_loops.png draws, a panel each: (title, deformation column, force column,
    stroke, stop) of each distinct element, the first of its ``count``; an isolator whose shear is
    a multiple shear spring (coupling = "mss") by its two shear lines (their deformation and the
    resultant along each), not by its n springs."""
    system = result.system
    panels, k, seen = [], 0, set()
    for el in system.elements:
        if el.role is not None and el.role.startswith("mss"):
            if el.isolator not in seen:
                seen.add(el.isolator)
                springs = sum(1 for e in system.elements if e.isolator == el.isolator and e.role.startswith("mss"))
                for j in (1, 2):
                    panels.append((f"iso{el.isolator} shear {j}: {el.hysteresis.split(' (')[0]} (mss {springs})",
                                   f"iso{el.isolator}_shear{j}_u_m",
                                   f"iso{el.isolator}_shear{j}_f_N", None, None))
            k += el.count
            continue
        label = f"e{k + 1}" if el.count == 1 else f"e{k + 1}-e{k + el.count} (each)"
        line = f"{el.angle_deg:g}°" if el.direction is None else el.line
        panels.append((f"{label}: {el.hysteresis}, {line}", f"e{k + 1}_u_m", f"e{k + 1}_f_N", el.stroke,
                       None if el.stop is None else el.stop[:2]))
        k += el.count
    return panels


@styled
def plot_element_loops(result: Result, path: Path):
    """Force against deformation of each distinct element (seed Fig. 4 style; an MSS isolator by
    its two shear lines: loop_panels), the stroke limits dashed and a stop's gaps dotted, each in
    a legend. Returns the figure (saved to ``path``)."""
    sample = result.plot.sample
    panels = loop_panels(result)
    n = len(panels)
    # the page's width in two columns up to four panels, three beyond (their rows must fit a page too)
    cols = min(n, 2 if n <= 4 else 3)
    rows = math.ceil(n / cols)
    fig, axes = subplots(rows, cols, figsize=(PRINT_WIDTH * cols / (2 if n <= 4 else 3), (3.0 if n <= 4 else 2.6) * rows),
                         squeeze=False)
    peak_f = [result.extremes.peak(f_col) for _, _, f_col, _, _ in panels]
    top = max(peak_f, default=0.0)
    for i, (title, u_col, f_col, stroke, stop) in enumerate(panels):
        ax = axes.flat[i]
        ax.set_title(title, fontsize=8, wrap=True)
        if peak_f[i] < NEGLIGIBLE * top:  # a panel of rounding noise would look like a loop
            at_rest(ax, f"at rest: |f| at most {peak_f[i]:.1e} N,\nbelow 1e-9 of the largest: rounding")
            continue
        u = sample[:, result.columns.index(u_col)]
        f = sample[:, result.columns.index(f_col)]
        ax.plot(u * 1e3, f * 1e-3, lw=0.7)
        view = loop_view(float(u.min()) * 1e3, float(u.max()) * 1e3, stroke)
        ax.set_xlim(*view)
        limits = [(stroke, "stroke limits", "C3", "--"), (stop, "stop gaps", "C2", ":")]
        for where, name, colour, style in limits:
            if where is None:
                continue
            lo, hi = where  # the deformation it can take, or where it bears on its stop: drawn where in view
            finite = [x * 1e3 for x in where if math.isfinite(x)]
            shown = [x for x in finite if view[0] <= x <= view[1]]
            said = f"{name} " + ", ".join(f"{'+' if x > 0 else ''}{plain_number(x)}" for x in finite) + " mm"
            if len(shown) < len(finite):
                said += ",\nbeyond the axis" if not shown else ",\none beyond the axis"
            for j, x in enumerate(shown):
                ax.axvline(x, color=colour, lw=0.9, ls=style, label=said if j == 0 else None)
            if not shown:  # (the legend's entry without a line in view)
                ax.plot([], [], color=colour, lw=0.9, ls=style, label=said)
        if stroke is not None or stop is not None:
            ax.legend(fontsize=8, loc="best", framealpha=0.9)
        ax.set_xlabel("u [mm]")
        ax.set_ylabel("f [kN]")
        # at most five labelled ticks a side: "-0.10 -0.05 0.00 0.05 0.10 0.15" runs together
        # in a panel this narrow
        ax.xaxis.set_major_locator(MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10], min_n_ticks=3))
        ax.yaxis.set_major_locator(MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]))
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    save(fig, path)
    return fig


def loop_view(lo: float, hi: float, stroke: tuple[float, float] | None) -> tuple[float, float]:
    """The deformation axis of a loop (mm) from the loop itself (from ``lo`` to ``hi``, 8 % beside
    it), widened to a stroke limit only where the loop would still fill half the axis: a +-4 mm
    loop under +-60 mm strokes is a loop, not a sliver."""
    span = max(hi - lo, 1e-12)
    a, b = lo - 0.08 * span, hi + 0.08 * span
    for limit in (x * 1e3 for x in stroke or ()):
        wider = (min(a, limit - 0.04 * span), max(b, limit + 0.04 * span))
        if span >= 0.5 * (wider[1] - wider[0]):
            a, b = wider
    return a, b


@styled
def plot_energy(result: Result, path: Path):
    """Cumulative input, kinetic and hysteretic energy, and the balance error. Input and
    hysteretic energy nearly coincide where little is kinetic or viscous: the input is a broad
    light band under the others, the hysteretic energy a dashed line on it. Returns the figure
    (saved to ``path``)."""
    fig, axes = subplots(2, 1, figsize=(PRINT_WIDTH, 4.8), sharex=True, height_ratios=(3, 1))
    _line(axes[0], result, "E_input_J", label="input", lw=3.5, color="C0", alpha=0.4, zorder=2,
          solid_capstyle="butt")
    _line(axes[0], result, "E_hysteretic_J", label="hysteretic\n(dissipated + stored)", lw=1.1, color="C1",
          ls=(0, (5, 2)), zorder=4)
    if "E_viscous_J" in result.columns:
        _line(axes[0], result, "E_viscous_J", label="viscous", lw=1.0, color="C2", zorder=3)
    _line(axes[0], result, "E_kinetic_J", label="kinetic", lw=0.7, color="C3", zorder=3)
    axes[0].set_ylabel("energy [J]")
    # beside the axes: inside, wherever it went, some scene's curves ran under it (a pulse's input
    # rises at once to the top left, a long record's kinetic energy runs along the bottom)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, borderaxespad=0.0)
    axes[0].set_title(f"Energy balance (relative error {result.energy_balance:.2e})")
    _line(axes[1], result, "E_error_J", lw=0.7, color="C4")  # (not the kinetic line's colour)
    axes[1].set_ylabel("error [J]")
    axes[1].set_xlabel("time [s]")
    left, _, bottom, top, gap = TIME_MARGINS
    save(fig, path, (left, ENERGY_LEGEND_WIDTH, bottom, top, gap))
    return fig


#: the right margin of energy.png that holds its legend, inches
ENERGY_LEGEND_WIDTH = 2.0


def write_plots(result: Result, out: Path) -> list[str]:
    """All the PNGs of a run (on two cores where it is safe: rbhyst.report.parallel); returns
    the file names written."""
    from functools import partial

    from rbhyst.report.parallel import draw_all

    if len(result.system.coordinates) == 6:
        from rbhyst.report.model3d import plot_body_3d

        jobs = {"model.png": partial(plot_body_3d, result, out / "model.png")}
    else:
        jobs = {"model.png": partial(plot_body, result, out / "model.png")}
    if result.layout.has_support:
        jobs["support_motion.png"] = partial(plot_excitation, result, out / "support_motion.png")
    for k, name in enumerate(response_files(result.system.coordinates)):
        jobs[name] = partial(plot_response, result, k, out / name)
    for name, _ in result.layout.points:
        jobs[f"response_{name}.png"] = partial(plot_point, result, name, out / f"response_{name}.png")
    jobs["element_loops.png"] = partial(plot_element_loops, result, out / "element_loops.png")
    if result.spectra is not None and result.spectra.kind == "srs":
        from rbhyst.report.shock_spectra import plot_located_pvss
        from rbhyst.report.spectra import plot_spectra

        jobs["srs.png"] = partial(plot_spectra, result.spectra.maximax_spectra(), out / "srs.png",
                                  title=result.system.title, shock=True)
        jobs["pvss.png"] = partial(plot_located_pvss, result.spectra, out / "pvss.png", title=result.system.title)
    elif result.spectra is not None:
        from rbhyst.report.spectra import plot_spectra

        jobs["spectra.png"] = partial(plot_spectra, result.spectra, out / "spectra.png", title=result.system.title)
    jobs["energy.png"] = partial(plot_energy, result, out / "energy.png")
    draw_all(list(jobs.values()))
    return list(jobs)
