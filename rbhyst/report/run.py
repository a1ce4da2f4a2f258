"""PNG plots of one analysis, after the seed's Figs. 3-8."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..results import Result
from ._style import plt, save


def plot_body(result: Result, path: Path) -> None:
    """The body, its vertices and its elements (seed Fig. 3a)."""
    system = result.system
    v = system.body.vertices
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    closed = np.vstack([v, v[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="0.9", zorder=1)
    ax.plot(closed[:, 0], closed[:, 1], color="0.2", lw=1.2, zorder=2)
    for i, (x, y) in enumerate(v, start=1):
        ax.annotate(f"P{i}", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8, color="0.3")
    ax.plot(0, 0, "k+", ms=10, zorder=3)
    ax.annotate("G", (0, 0), textcoords="offset points", xytext=(5, -10))
    size = float(np.ptp(v, axis=0).max())
    length = 0.18 * size
    k = 1
    for el in system.elements:
        x, y = el.x
        a = math.radians(el.angle_deg)
        # along its line of action, on the side away from G: clear of the body's outline
        side = 1.0 if x * math.cos(a) + y * math.sin(a) >= 0.0 else -1.0
        ex, ey = x + side * length * math.cos(a), y + side * length * math.sin(a)
        ax.plot([ex, x], [ey, y], color="C0", lw=2.5, solid_capstyle="round", zorder=4)
        ax.plot(ex, ey, marker="s", color="C0", ms=5, zorder=4)
        label = f"e{k}" if el.count == 1 else f"e{k}-{k + el.count - 1}"
        ax.annotate(label, (ex, ey), textcoords="offset points", xytext=(-6, -11), fontsize=7, color="C0")
        k += el.count
    ex = result.system.excitation
    if ex.p1 is not None or ex.p2 is not None or ex.m3 is not None:
        ax.plot(*ex.point, marker="*", color="C3", ms=12, zorder=5)
        ax.annotate("P (loads)", ex.point, textcoords="offset points", xytext=(6, 6), color="C3")
    ax.set_aspect("equal")
    ax.margins(0.15)
    ax.set_xlabel("x1 [m]")
    ax.set_ylabel("x2 [m]")
    title = system.title or "Model"
    ax.set_title(f"{title}\nA = {system.body.area:.4g} m², m = {system.mass[0]:.6g} kg, "
                 f"J = {system.mass[2]:.6g} kg m²", fontsize=9)
    save(fig, path)


def plot_excitation(result: Result, path: Path) -> None:
    """Support acceleration along x1 and x2 (seed Fig. 5)."""
    t = result.time
    fig, axes = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True)
    for k, ax in enumerate(axes):
        ax.plot(t, result.ag[:, k], lw=0.7, color="C0")
        ax.set_ylabel(f"ag{k + 1} [m/s²]")
    axes[0].set_title("Support acceleration")
    axes[-1].set_xlabel("time [s]")
    save(fig, path)


def plot_response(result: Result, k: int, path: Path) -> None:
    """Relative displacement and total acceleration of coordinate k (seed Figs. 6-8)."""
    labels = [("u1 [m]", "at1 [m/s²]"), ("u2 [m]", "at2 [m/s²]"), ("θ3 [rad]", "θt3'' [rad/s²]")]
    names = ["mass centre along x1", "mass centre along x2", "rotation about x3"]
    t = result.time
    fig, axes = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True)
    axes[0].plot(t, result.d[:, k], lw=0.8, color="C0")
    axes[0].set_ylabel(labels[k][0])
    axes[0].set_title(f"Relative displacement and total acceleration: {names[k]}")
    axes[1].plot(t, result.total_acceleration[:, k], lw=0.6, color="C1")
    axes[1].set_ylabel(labels[k][1])
    axes[1].set_xlabel("time [s]")
    save(fig, path)


def plot_element_loops(result: Result, path: Path) -> None:
    """Force against deformation of each distinct element (seed Fig. 4 style)."""
    system = result.system
    n = len(system.elements)
    cols = min(n, 3)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols, 3.0 * rows), squeeze=False)
    k = 0
    for i, el in enumerate(system.elements):
        ax = axes.flat[i]
        ax.plot(result.element_u[:, k] * 1e3, result.element_f[:, k] * 1e-3, lw=0.7)
        label = f"e{k + 1}" if el.count == 1 else f"e{k + 1}-e{k + el.count} (each)"
        ax.set_title(f"{label}: {el.hysteresis}, {el.angle_deg:g}°", fontsize=8)
        ax.set_xlabel("u [mm]")
        ax.set_ylabel("f [kN]")
        k += el.count
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    save(fig, path)


def plot_energy(result: Result, path: Path) -> None:
    """Cumulative input, kinetic and hysteretic energy, and the balance error."""
    t = result.time
    e_in, e_kin, e_hyst = result.energy.T
    fig, axes = plt.subplots(2, 1, figsize=(8, 4.8), sharex=True, height_ratios=(3, 1))
    axes[0].plot(t, e_in, label="input", lw=1.0)
    axes[0].plot(t, e_hyst, label="hysteretic (dissipated + stored)", lw=1.0)
    axes[0].plot(t, e_kin, label="kinetic", lw=0.7)
    axes[0].set_ylabel("energy [J]")
    axes[0].legend(loc="upper left", fontsize=8)
    axes[0].set_title(f"Energy balance (relative error {result.energy_balance:.2e})")
    axes[1].plot(t, result.energy_error, lw=0.7, color="C3")
    axes[1].set_ylabel("error [J]")
    axes[1].set_xlabel("time [s]")
    save(fig, path)


def write_plots(result: Result, out: Path) -> list[str]:
    """All the PNGs of a run; returns the file names written."""
    written = []

    def do(fn, name, *args):
        fn(result, *args, out / name)
        written.append(name)

    do(plot_body, "model.png")
    if result.ag is not None:
        do(plot_excitation, "support_motion.png")
    for k, name in enumerate(("response_x1.png", "response_x2.png", "response_theta3.png")):
        do(plot_response, name, k)
    do(plot_element_loops, "element_loops.png")
    do(plot_energy, "energy.png")
    return written
