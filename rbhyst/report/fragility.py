"""fragility.png: for each limit state, the fitted curve P(reach | x), its bootstrap band and the
share of cases reaching the limit at each intensity level (one colour per vary combination)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rbhyst.report._style import save, styled, subplots

MAX_GROUPS = 8  # vary combinations drawn per panel


@styled
def plot_fragility(curves, label: str, vary_keys: list[str], path: Path, confidence: float = 0.9):
    """A panel per limit state: each vary combination's curve and band, the share of cases reaching
    the limit at each intensity with its count (3/7), or why no curve was fitted. Returns the
    figure (saved to ``path``)."""
    by_state: dict[str, list] = {}
    for c in curves:
        by_state.setdefault(c.limit_state.name, []).append(c)
    n = len(by_state)
    cols = min(n, 2)
    rows = -(-n // cols)
    fig, axes = subplots(rows, cols, figsize=(5.6 * cols, 4.0 * rows), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax, (name, members) in zip(axes.ravel(), by_state.items()):
        ls = members[0].limit_state
        several = len(members) > 1
        refused = []
        for g, c in enumerate(members[:MAX_GROUPS]):
            colour = f"C{g}" if several else "C0"
            group = ", ".join(f"{k} = {v}" for k, v in zip(vary_keys, c.group)) if several else ""
            keep = c.n > 0
            if c.fitted:
                from rbhyst.analyses.fragility import probability

                if c.band is not None:
                    ax.fill_between(c.grid, *c.band, color=colour, alpha=0.18, lw=0,
                                    label=None if several else
                                    f"{100 * confidence:g} % band ({c.identified} resamples)")
                text = f"median {c.median:.3g}, beta {c.beta:.2f}"
                ax.plot(c.grid, probability(c.grid, c.median, c.beta), "-", color=colour, lw=1.8,
                        label=f"{group}: {text}" if several else f"fit: {text}")
            else:
                refused.append(f"{group + ': ' if group else ''}not fitted: {c.message}")
            # a combination without a curve names its markers in the legend itself
            marks = ("share of cases reaching it" if not several else None if c.fitted else
                     f"{group}: share reaching it (not fitted)")
            ax.plot(c.x[keep], c.z[keep] / c.n[keep], "o", ms=5, mfc="white", mec=colour, mew=1.4, label=marks)
            for x, z, m in zip(c.x[keep], c.z[keep], c.n[keep]):  # each stripe's count: 3/7
                ax.annotate(f"{z}/{m}", (x, z / m), textcoords="offset points", xytext=(0, 5 + 9 * g), ha="center",
                            va="bottom", fontsize=7, color=colour if several else "0.35")
        if refused:
            ax.text(0.02, 0.97, "\n".join(_wrap(t, 52) for t in refused), transform=ax.transAxes, va="top",
                    fontsize=6.5, color="C3", bbox={"fc": "white", "ec": "C3", "alpha": 0.85, "lw": 0.6})
        ax.set_ylim(-0.03, 1.08)
        ax.set_xlim(left=0.0)
        ax.set_xlabel(label)
        ax.set_ylabel("P(reach)")
        ax.set_title(f"{name}: {ls.quantity} >= {ls.limit:g}", fontsize=9)
        if ax.get_legend_handles_labels()[0]:
            # (a curve rising to the right leaves the middle of the right side free; the lower right
            # holds the high intensities' shares of an unfitted combination)
            ax.legend(fontsize=6.5, loc="center right")
    fig.suptitle("Fragility: maximum likelihood on the stripes, bootstrap band")
    save(fig, path)
    return fig


def _wrap(text: str, width: int) -> str:
    words, lines, line = text.split(), [], ""
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}".strip()
    lines.append(line)
    return "\n".join(lines)
