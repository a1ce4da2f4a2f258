"""Plots of ``rbhyst sweep`` from its cases table: IDA curves, the spread over vary values,
and the peaks of a suite of motions at one level.

- ``ida.png`` (two scale levels or more): the scale level against each motion's peak
  response, one thin line per motion, the median and 84th percentile over the motions thick
  (one colour per vary combination when there are several).
- ``vary.png`` (a vary or cases key with two values or more): each case's peak against the
  key's value, coloured by scale level, with the median over everything else at each value.
- ``motions.png`` (one level, nothing varied): each motion's peak, with mean, median and
  84th percentile.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import MaxNLocator

from rbhyst.analyses.sweep.tables import PERCENTILE
from rbhyst.report._style import save, styled, subplots
from rbhyst.report.fragility import plot_fragility  # noqa: F401 (the sweep's plotter draws fragility.png too)

PLOT_FILES = ("ida.png", "vary.png", "motions.png")
#: the peaks drawn, where the cases have them (every peak is in cases.csv and stats.csv)
PREFERRED = ("peak_u1_m", "peak_u2_m", "peak_theta3_rad", "peak_at1_m_s2", "peak_at2_m_s2")
MAX_GROUPS = 8  # vary combinations drawn in ida.png
MAX_KEYS = 4  # vary keys drawn in vary.png


def write_plots(header: list[str], rows: list[list], vary_keys: list[str], scale_kind: str, folder: Path) -> list[str]:
    """The plots that fit the sweep's axes, into ``folder``; returns their names."""
    cases = _records(header, rows, vary_keys)
    ok = [c for c in cases if c["status"] == "ok"]
    quantities = _quantities(header, ok)
    if not ok or not quantities:
        return []
    written = []
    levels = sorted({c["scale"] for c in cases})
    varied = [k for k in vary_keys if len({c["vary"][k] for c in cases}) > 1]
    scale_label = "target PGA [g]" if scale_kind == "pga_g" else "scale factor"
    if len(levels) > 1:
        plot_ida(ok, quantities, varied, scale_label, Path(folder) / "ida.png")
        written.append("ida.png")
    if varied:
        plot_vary(ok, quantities[:3], varied[:MAX_KEYS], scale_label, Path(folder) / "vary.png")
        written.append("vary.png")
    if len(levels) == 1 and not varied:
        plot_motions(ok, quantities, Path(folder) / "motions.png")
        written.append("motions.png")
    return written


def _records(header, rows, vary_keys) -> list[dict]:
    i = {h: k for k, h in enumerate(header)}
    out = []
    for r in rows:
        peaks = {h: float(r[k]) for h, k in i.items() if h.startswith("peak_") and r[k] != ""}
        out.append({"motion": r[i["motion"]], "scale": float(r[i["scale"]]), "status": r[i["status"]],
                    "vary": {k: r[i[k]] for k in vary_keys}, "peaks": peaks})
    return out


def _quantities(header, ok) -> list[str]:
    have = {p for c in ok for p in c["peaks"]}
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


@styled
def plot_ida(ok, quantities, vary_keys, scale_label, path: Path) -> None:
    groups = _groups(ok, vary_keys)
    shown = list(groups.items())[:MAX_GROUPS]
    several = len(groups) > 1
    fig, axes = _grid(len(quantities), legend=True)
    for ax, q in zip(axes, quantities):
        for g, (ident, members) in enumerate(shown):
            colour = f"C{g}" if several else "k"
            by_motion: dict[str, list[tuple[float, float]]] = {}
            for c in members:
                if q in c["peaks"]:
                    by_motion.setdefault(c["motion"], []).append((c["scale"], c["peaks"][q]))
            for m, pts in by_motion.items():
                pts.sort()
                ax.plot([p for _, p in pts], [s for s, _ in pts], "-o", ms=2.5, lw=0.8,
                        color=colour if several else "0.65", alpha=0.35 if several else 1.0)
            levels = sorted({c["scale"] for c in members})
            med, p84 = [], []
            for s in levels:
                x = np.array([c["peaks"][q] for c in members if c["scale"] == s and q in c["peaks"]])
                med.append(np.median(x) if len(x) else np.nan)
                p84.append(np.percentile(x, PERCENTILE) if len(x) else np.nan)
            name = ", ".join(f"{k} = {v}" for k, v in zip(vary_keys, ident)) if several else ""
            ax.plot(med, levels, "-", lw=2.2, color=colour, label=f"median {name}".strip())
            ax.plot(p84, levels, "--", lw=2.0, color=colour, label=f"84th percentile {name}".strip())
        ax.set_xlabel(_label(q))
        ax.set_ylabel(scale_label)
    axes[0].plot([], [], "-o", ms=2.5, lw=0.8, color="0.65", label="each motion")
    _legend_cell(axes, len(quantities))
    motions = len({c["motion"] for c in ok})
    more = f" (first {MAX_GROUPS} of {len(groups)} vary combinations)" if len(groups) > MAX_GROUPS else ""
    fig.suptitle(f"Incremental dynamic analysis: {motions} motion{'s' * (motions != 1)}{more}")
    save(fig, path)


def _positions(values: list[str]) -> tuple[dict[str, float], list[str] | None]:
    """Numeric values at their value; anything else at 0, 1, 2 ... with its text as tick label."""
    try:
        return {v: float(v) for v in values}, None
    except ValueError:
        order = list(dict.fromkeys(values))
        return {v: float(i) for i, v in enumerate(order)}, order


@styled
def plot_vary(ok, quantities, keys, scale_label, path: Path) -> None:
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
                xs = np.unique(x)
                ax.plot(xs, [np.median(y[x == v]) for v in xs], "-", lw=1.8, color=colour,
                        label=f"{scale_label} {s:g}: median")
            if ticks is not None:
                ax.set_xticks(range(len(ticks)), ticks, rotation=20, fontsize=7)
            ax.set_xlabel(key)
            ax.set_ylabel(_label(q))
    axes[0, 0].legend(fontsize=6.5)
    fig.suptitle("Peak response against the varied values (points: every case; lines: median over the rest)")
    save(fig, path)


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
