"""Plots of ``rbhyst sweep`` from its cases table: IDA curves, the spread over vary values,
and the peaks of a suite of motions at one level.

- ``ida.png`` (two scale levels or more): the scale level against each motion's peak
  response, one thin line per motion, the median and 84th percentile over the motions thick;
  with several vary combinations, the median of each (its 84th percentile is in stats.csv), the
  first varied key's values told by colour, the second's by line style, the third's by marker,
  one legend entry per value.
- ``vary.png`` (a vary or cases key with two values or more): each case's peak displacements
  and accelerations against the key's value (with its unit), coloured by scale level, with the
  median over everything else at each value.
- ``motions.png`` (one level, nothing varied): each motion's peak, with mean, median and
  84th percentile.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import MaxNLocator

from rbhyst.analyses.sweep.tables import PERCENTILE
from rbhyst.report._style import plain_number, save, styled, subplots
from rbhyst.report.fragility import plot_fragility  # noqa: F401 (the sweep's plotter draws fragility.png too)
from rbhyst.report.sweep_files import PLOT_FILES  # noqa: F401 (the plotter's files, named without matplotlib)

#: the peaks drawn, where the cases have them (every peak is in cases.csv and stats.csv)
PREFERRED = ("peak_u1_m", "peak_u2_m", "peak_theta3_rad", "peak_at1_m_s2", "peak_at2_m_s2")
#: those of vary.png: displacements and accelerations
VARY_PEAKS = ("peak_u1_m", "peak_u2_m", "peak_at1_m_s2", "peak_at2_m_s2")
MAX_KEYS = 4  # vary keys drawn in vary.png
#: how ida.png tells the varied keys' values apart: the first key by colour, the second by
#: line style, the third by marker (more keys or values: one colour per combination)
COLOURS = tuple(f"C{i}" for i in range(10))
STYLES = ("-", "--", ":", "-.")
MARKERS = ("o", "s", "^", "D", "v", "P")


def write_plots(header: list[str], rows: list[list], vary_keys: list[str], scale_kind: str, folder: Path,
                units: dict[str, str | None] | None = None) -> list[str]:
    """The plots that fit the sweep's axes, into ``folder``; returns their names. ``units``:
    the unit of each vary key (rbhyst.model.deck.key_unit), for the axes and legends."""
    # (the peaks drawn only: a case's record of every peak took kilobytes at 10^5 cases)
    quantities = _quantities(header, _filled(header, rows))
    cases = _records(header, rows, vary_keys, quantities)
    ok = [c for c in cases if c["status"] == "ok"]
    if not ok or not quantities:
        return []
    units = units or {}
    written = []
    levels = sorted({c["scale"] for c in cases})
    varied = [k for k in vary_keys if len({c["vary"][k] for c in cases}) > 1]
    scale_label = "target PGA [g]" if scale_kind == "pga_g" else "scale factor"
    if len(levels) > 1:
        plot_ida(ok, quantities, varied, scale_label, Path(folder) / "ida.png", units)
        written.append("ida.png")
    if varied:
        shown = [q for q in VARY_PEAKS if q in quantities] or quantities[:4]
        plot_vary(ok, shown, varied[:MAX_KEYS], scale_label, Path(folder) / "vary.png", units)
        written.append("vary.png")
    if len(levels) == 1 and not varied:
        plot_motions(ok, quantities, Path(folder) / "motions.png")
        written.append("motions.png")
    return written


def _filled(header, rows) -> set[str]:
    """The peak columns that a finished case has a value of."""
    i = {h: k for k, h in enumerate(header)}
    status = i["status"]
    left = {h: k for h, k in i.items() if h.startswith("peak_")}
    have = set()
    for r in rows:
        if not left:
            break
        if r[status] == "ok":
            for h in [h for h, k in left.items() if r[k] != ""]:
                have.add(h)
                del left[h]
    return have


def _records(header, rows, vary_keys, peaks=None) -> list[dict]:
    """Each row as {motion, scale, status, vary, peaks}, with the ``peaks`` named (every one)."""
    i = {h: k for k, h in enumerate(header)}
    wanted = [(h, k) for h, k in i.items() if h.startswith("peak_") and (peaks is None or h in peaks)]
    out = []
    for r in rows:
        got = {h: float(r[k]) for h, k in wanted if r[k] != ""}
        out.append({"motion": r[i["motion"]], "scale": float(r[i["scale"]]), "status": r[i["status"]],
                    "vary": {k: r[i[k]] for k in vary_keys}, "peaks": got})
    return out


def _quantities(header, have: set[str]) -> list[str]:
    """The peaks drawn, of those the finished cases have (``have``)."""
    chosen = [q for q in PREFERRED if q in have]
    return chosen or [h for h in header if h in have][:4]


def _label(q: str) -> str:
    name, _, unit = q[len("peak_"):].partition("_")
    unit = unit.replace("_", "/").replace("m/s2", "m/s²").replace("rad/s2", "rad/s²")
    return f"peak |{name}| [{unit}]" if unit else f"peak |{name}|"


def _grid(n: int, cols: int = 3, legend: bool = False):
    """Panels for n plots; with ``legend``, one more cell for it (the last, kept blank)."""
    cells = n + legend
    cols = min(cols, cells)
    rows = -(-cells // cols)
    fig, axes = subplots(rows, cols, figsize=(4.2 * cols, 3.5 * rows), squeeze=False)
    for ax in axes.ravel()[:n]:
        ax.xaxis.set_major_locator(MaxNLocator(5))
        ax.ticklabel_format(axis="x", style="sci", scilimits=(-2, 4), useMathText=True)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    return fig, axes.ravel()


def _legend_cell(axes, n: int) -> None:
    """The legend of the first panel, in the blank cell after the n panels."""
    handles, labels = axes[0].get_legend_handles_labels()
    axes[n].legend(handles, labels, loc="center", fontsize=7, frameon=False)


def _groups(cases, vary_keys) -> dict[tuple, list[dict]]:
    out: dict[tuple, list[dict]] = {}
    for c in cases:
        out.setdefault(tuple(c["vary"][k] for k in vary_keys), []).append(c)
    return out


def key_label(key: str, units: dict[str, str | None]) -> str:
    """A vary key with its unit: ``body.mass [kg]``; a pure number or an unknown unit bare."""
    unit = units.get(key)
    return f"{key} [{unit}]" if unit else key


def _value(v: str) -> str:
    """A vary value as a label shows it: numbers shortest (200000.0 -> 200000), text as it is."""
    try:
        return plain_number(float(v))
    except ValueError:
        return v


def _ordered(values) -> list[str]:
    """Distinct values, numbers in ascending order, anything else as it comes."""
    distinct = list(dict.fromkeys(values))
    try:
        return sorted(distinct, key=float)
    except ValueError:
        return distinct


def _encoding(idents: list[tuple], vary_keys: list[str]):
    """How each combination is drawn: {ident: (colour, line style, marker)}, and the legend's
    (label, style) entries. Keys map to colour, line style and marker in turn while their
    values fit those; otherwise every combination gets a colour of a sequential map."""
    values = [_ordered(i[k] for i in idents) for k in range(len(vary_keys))]
    channels = (COLOURS, STYLES, MARKERS)
    if len(vary_keys) <= len(channels) and all(len(v) <= len(c) for v, c in zip(values, channels)):
        look = {}
        for ident in idents:
            pick = [channels[k][values[k].index(ident[k])] for k in range(len(vary_keys))]
            pick += [None] * (3 - len(pick))
            look[ident] = (pick[0], pick[1] or "-", pick[2])
        return look, values
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    n = max(1, len(idents) - 1)
    return {ident: (cmap(0.9 * i / n), "-", None) for i, ident in enumerate(idents)}, None


@styled
def plot_ida(ok, quantities, vary_keys, scale_label, path: Path, units: dict | None = None):
    """Returns the figure (saved to ``path``)."""
    units = units or {}
    groups = _groups(ok, vary_keys)
    several = len(groups) > 1
    idents = sorted(groups, key=lambda ident: [(_num(v), v) for v in ident])
    look, values = _encoding(idents, vary_keys) if several else ({(): ("k", "-", None)}, None)
    fig, axes = _grid(len(quantities), legend=True)
    # (many combinations, one colour each: one collection a panel, not an artist each, which
    # took seconds and megabytes per thousand combinations)
    together = several and values is None
    for ax, q in zip(axes, quantities):
        lines = []
        for ident, (levels, med, p84) in _medians(groups, idents, q, with_p84=not several):
            colour, style, marker = look[ident]
            if not several:  # one line per motion; with several combinations they would be a tangle
                by_motion: dict[str, list[tuple[float, float]]] = {}
                for c in groups[ident]:
                    if q in c["peaks"]:
                        by_motion.setdefault(c["motion"], []).append((c["scale"], c["peaks"][q]))
                for m, pts in by_motion.items():
                    pts.sort()
                    ax.plot([p for _, p in pts], [s for s, _ in pts], "-o", ms=2.5, lw=0.8, color="0.65")
            if together:
                lines.append((np.column_stack([med, levels]), colour))
                continue
            ax.plot(med, levels, ls=style, lw=2.0, color=colour, marker=marker, ms=4)
            if not several:
                ax.plot(p84, levels, "--", lw=2.0, color=colour)
        if lines:
            from matplotlib.collections import LineCollection

            ax.add_collection(LineCollection([xy for xy, _ in lines], colors=[c for _, c in lines], linewidths=2.0,
                                             capstyle="projecting", joinstyle="round", zorder=2), autolim=True)
            ax.autoscale_view()
        ax.set_xlabel(_label(q))
        ax.set_ylabel(scale_label)
    cell = axes[len(quantities)]
    if values is None and len(idents) > MAX_ENTRIES:
        _colour_key(fig, cell, vary_keys, units, idents, look)
    else:
        cell.legend(*_ida_legend(vary_keys, units, idents, look, values), loc="center", fontsize=7, frameon=False)
    motions = len({c["motion"] for c in ok})
    heading = f"Incremental dynamic analysis: {motions} motion{'s' * (motions != 1)}"
    if several:
        heading += (f"; the median over the motions of each of {len(groups)} combinations "
                    f"(84th percentiles in stats.csv)")
    fig.suptitle(heading)
    save(fig, path)
    return fig


#: combinations a legend lists one by one; more are told by a colour bar
MAX_ENTRIES = 12


def _medians(groups: dict, idents: list, q: str, with_p84: bool):
    """(ident, (levels, medians, 84th percentiles or None)) of each combination in ``idents``:
    over its motions at each of its levels, the peaks ``q`` they have (nan where none has it).
    The sets of equal size go through numpy at once, a row each (it reduces a row as it would
    the row alone): one call per combination and level took seconds at thousands of them."""
    cells = []  # (ident, levels, the values at each level)
    for ident in idents:
        at: dict[float, list[float]] = {}
        for c in groups[ident]:
            at.setdefault(c["scale"], [])
            if q in c["peaks"]:
                at[c["scale"]].append(c["peaks"][q])
        levels = sorted(at)
        cells.append((ident, levels, [at[s] for s in levels]))
    by_size: dict[int, list[list[float]]] = {}
    for _, _, xs in cells:
        for x in xs:
            by_size.setdefault(len(x), []).append(x)
    stats = {}
    for n, xs in by_size.items():
        if n == 0:
            stats[0] = iter([(np.nan, np.nan)] * len(xs))
            continue
        m = np.array(xs, dtype=float)
        med = np.median(m, axis=1).tolist()
        p84 = np.percentile(m, PERCENTILE, axis=1).tolist() if with_p84 else [None] * len(xs)
        stats[n] = iter(zip(med, p84))
    out = []
    for ident, levels, xs in cells:
        got = [next(stats[len(x)]) for x in xs]
        out.append((ident, (levels, [g[0] for g in got], [g[1] for g in got] if with_p84 else None)))
    return out


def _colour_key(fig, cell, vary_keys, units, idents, look) -> None:
    """A colour bar in the legend's cell for many combinations drawn one colour each: a colour a
    combination in their order, at most MAX_ENTRIES of them labelled (every one is in stats.csv)."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import BoundaryNorm, ListedColormap

    n = len(idents)
    cmap = ListedColormap([look[ident][0] for ident in idents])
    bar = fig.colorbar(ScalarMappable(norm=BoundaryNorm(np.arange(n + 1) - 0.5, n), cmap=cmap),
                       ax=cell, location="left", fraction=0.12, shrink=0.9, aspect=25)
    ticks = np.unique(np.linspace(0, n - 1, MAX_ENTRIES).round().astype(int))
    bar.set_ticks(ticks, labels=[", ".join(_value(v) for v in idents[i]) for i in ticks], fontsize=7)
    bar.minorticks_off()
    bar.set_label(", ".join(key_label(k, units) for k in vary_keys) + " (median over the motions)", fontsize=7)


def _num(v: str) -> float:
    try:
        return float(v)
    except ValueError:
        return float("inf")


def _ida_legend(vary_keys, units, idents, look, values):
    """Handles and labels: the lines of one combination, or each key's values under its name."""
    from matplotlib.lines import Line2D

    def entry(label, **kw):
        return Line2D([], [], **kw), label

    if len(idents) == 1:
        rows = [entry("each motion", color="0.65", marker="o", ms=2.5, lw=0.8),
                entry("median over the motions", color="k", lw=2.0),
                entry("84th percentile", color="k", lw=2.0, ls="--")]
    elif values is None:  # one colour per combination
        rows = [entry(", ".join(key_label(k, units) for k in vary_keys), ls="none")]
        rows += [entry(", ".join(_value(v) for v in ident), color=look[ident][0], lw=2.0) for ident in idents]
    else:
        rows = []
        for k, key in enumerate(vary_keys):
            rows.append(entry(f"{key_label(key, units)}:", ls="none"))
            for i, v in enumerate(values[k]):
                kw = ({"color": COLOURS[i]} if k == 0 else {"color": "0.3", "ls": STYLES[i]} if k == 1 else
                      {"color": "0.3", "ls": "none", "marker": MARKERS[i], "ms": 4})
                rows.append(entry(f"  {_value(v)}", lw=2.0, **kw))
        rows.append(entry("(median over the motions)", ls="none"))
    return [h for h, _ in rows], [label for _, label in rows]


def _positions(values: list[str]) -> tuple[dict[str, float], list[str] | None]:
    """Numeric values at their value; anything else at 0, 1, 2 ... with its text as tick label."""
    try:
        return {v: float(v) for v in values}, None
    except ValueError:
        order = list(dict.fromkeys(values))
        return {v: float(i) for i, v in enumerate(order)}, order


@styled
def plot_vary(ok, quantities, keys, scale_label, path: Path, units: dict | None = None):
    """Returns the figure (saved to ``path``)."""
    units = units or {}
    levels = sorted({c["scale"] for c in ok})
    fig, axes = subplots(len(keys), len(quantities), figsize=(4.2 * len(quantities), 3.3 * len(keys)),
                             squeeze=False)
    for r, key in enumerate(keys):
        values = [c["vary"][key] for c in ok if c["vary"][key] != ""]
        pos, ticks = _positions(values)
        for col, q in enumerate(quantities):
            ax = axes[r, col]
            for li, s in enumerate(levels):
                pts = [(pos[c["vary"][key]], c["peaks"][q]) for c in ok
                       if c["scale"] == s and q in c["peaks"] and c["vary"][key] != ""]
                if not pts:
                    continue
                x = np.array([p[0] for p in pts])
                y = np.array([p[1] for p in pts])
                colour = f"C{li % 10}"
                ax.plot(x, y, "o", ms=3, alpha=0.45, color=colour)
                xs, med = _median_at(x, y)
                ax.plot(xs, med, "-", lw=1.8, color=colour, label=f"{scale_label} {s:g}: median")
            if ticks is not None:
                ax.set_xticks(range(len(ticks)), ticks, rotation=20, fontsize=7)
            elif len(set(pos.values())) <= 8:  # at the values themselves, as the sweep gives them
                at = sorted(set(pos.values()))
                ax.set_xticks(at, [plain_number(v) for v in at], fontsize=7,
                              rotation=20 if max(len(plain_number(v)) for v in at) > 5 else 0)
            ax.set_xlabel(key_label(key, units))
            ax.set_ylabel(_label(q))
    axes[0, 0].legend(fontsize=6.5)
    fig.suptitle("Peak response against the varied values (points: every case; lines: median over the rest)")
    save(fig, path)
    return fig


def _median_at(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, list[float]]:
    """Each distinct x (ascending) and the median of the y at it: the sets of equal size a matrix
    at a time, a row each (a call per value took a second at 2,000 values)."""
    xs, which = np.unique(x, return_inverse=True)
    order = np.argsort(which, kind="stable")
    bounds = np.searchsorted(which[order], np.arange(len(xs) + 1))
    sizes = np.diff(bounds)
    med = np.empty(len(xs))
    for n in np.unique(sizes):
        at = np.flatnonzero(sizes == n)
        rows = order[bounds[at][:, None] + np.arange(n)[None, :]]
        med[at] = np.median(y[rows], axis=1)
    return xs, med.tolist()


@styled
def plot_motions(ok, quantities, path: Path) -> None:
    fig, axes = _grid(len(quantities))
    for ax, q in zip(axes, quantities):
        pts = [(c["motion"], c["peaks"][q]) for c in ok if q in c["peaks"]]
        names = [m for m, _ in pts]
        y = np.array([v for _, v in pts])
        ax.bar(range(len(y)), y, color="0.7")
        for value, style, name in ((np.mean(y), ":", "mean"), (np.median(y), "-", "median"),
                                   (np.percentile(y, PERCENTILE), "--", "84th percentile")):
            ax.axhline(value, ls=style, color="k", lw=1.4, label=f"{name} {value:.4g}")
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=7)
        ax.set_ylabel(_label(q))
        ax.legend(fontsize=6.5)
    fig.suptitle(f"Peaks over {len({c['motion'] for c in ok})} motions")
    save(fig, path)
