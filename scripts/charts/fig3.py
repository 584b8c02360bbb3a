"""Figure 3 of the paper: orbits of the n-body tasks (truth, baseline, HNN on equal axes), the
coordinate MSE and the total energy (fig3_<task>)."""

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, LABELS, MODELS, TITLES, save
from .rollout import clamp_limits, energy_summary, plot_energy_panel, plot_mse_panel

def plot_orbits(ax, t, states, n_bodies, color, limits, title):
    """x vs y of every body; states columns are (qx1..qxn, qy1..qyn, px.., py..). Says so when
    the orbit leaves the shared frame or the state stops being finite."""
    styles = ["-", "--", ":", "-."]
    for b in range(n_bodies):
        x, y = states[:, b], states[:, n_bodies + b]
        alpha = 1.0 - 0.55 * b / max(n_bodies - 1, 1)  # later bodies lighter, and dashed
        ax.plot(x, y, styles[b % 4], color=color, alpha=alpha, lw=1.3, label=f"body {b + 1}")
        ax.plot(x[0], y[0], "o", color=color, alpha=alpha, ms=4)
    positions = states[:, :2 * n_bodies]
    finite = np.all(np.isfinite(positions), axis=1)
    remarks = []
    if np.any((positions[finite] < limits[0]) | (positions[finite] > limits[1])):
        remarks.append("leaves the frame")
    if not np.all(finite):
        remarks.append(f"not finite from t = {t[np.argmin(finite)]:.3g}")
    if remarks:
        ax.text(0.03, 0.03, "; ".join(remarks), transform=ax.transAxes, fontsize=7,
                style="italic", color=color)
    ax.set_xlim(*limits)
    ax.set_ylim(*limits)
    ax.set_aspect("equal")
    ax.set(title=title, xlabel="x", ylabel="y")
    ax.legend(loc="upper right")


def draw_fig3(results, task, runs, rolls, truth):
    """Paper Figure 3: orbits of test trajectory 0 (truth, baseline, HNN on equal axes), the
    coordinate MSE over all test rollouts, and total energy of trajectory 0."""
    n_bodies = truth["true"].shape[1] // 4
    pos = slice(0, 2 * n_bodies)
    every = np.concatenate([truth["true"][:, pos]] + [r.shown["pred"][:, pos]
                                                       for r in rolls.values()])
    limits = clamp_limits(truth["true"][:, pos], every, margin=0.5) or (-1.0, 1.0)
    fig, axes = plt.subplots(1, 5, figsize=(20, 4.2), layout="constrained",
                             gridspec_kw={"width_ratios": [1, 1, 1, 1.25, 1.25]})
    plot_orbits(axes[0], truth["t"], truth["true"], n_bodies, COLORS["truth"], limits,
                LABELS["truth"])
    for ax, model in zip(axes[1:3], MODELS):
        if model in rolls:
            tr = rolls[model].shown
            plot_orbits(ax, tr["t"], tr["pred"], n_bodies, COLORS[model], limits, LABELS[model])
        else:
            ax.set_title(LABELS[model])
            ax.text(0.5, 0.5, "no rollout", ha="center", transform=ax.transAxes)
    plot_mse_panel(axes[3], rolls)
    plot_energy_panel(axes[4], rolls, truth)
    t_end = truth["t"][-1]
    fig.suptitle(f"{TITLES.get(task, task)}: test trajectory 0, t = 0..{t_end:g}"
                 f"{energy_summary(runs)}")
    return save(fig, results, f"fig3_{task}")
