"""Relative energy error over long horizons, true systems and a trained HNN (energy_drift), from
energy_drift.csv of bench/accuracy/work_precision."""

import os

import matplotlib.pyplot as plt

from .common import read_rows, save
from .work_precision import METHOD_STYLE, SYSTEMS


def plot_energy_drift(directory):
    rows = read_rows(os.path.join(directory, "energy_drift.csv"))
    systems = [s for s in ("spring", "pendulum", "2body", "hnn_spring")
               if any(r["system"] == s for r in rows)]
    fig, axes = plt.subplots(2, 2, figsize=(10, 8), sharey=True)
    for ax, system in zip(axes.flat, systems):
        learned = system == "hnn_spring"
        for method, style in METHOD_STYLE.items():
            for quantity in ("learned_H", "true_H"):
                points = sorted((float(r["periods"]), float(r["error"])) for r in rows
                                if r["system"] == system and r["method"] == method
                                and r["quantity"] == quantity)
                if not points:
                    continue
                name = style["label"].split(" (")[0]
                if learned:
                    name += ": learned H" if quantity == "learned_H" else ": true spring H"
                ls = ":" if learned and quantity == "true_H" else "-"
                ax.plot(*zip(*points), color=style["color"], ls=ls, lw=1.3, label=name)
        title = SYSTEMS.get(system, system)
        if learned:
            title += "\nnon-separable H (no leapfrog/Yoshida); periods of the true spring"
            ax.legend(loc="lower right", fontsize=7)
        ax.set(xscale="log", yscale="log", ylim=(1e-16, 10), title=title)
    for ax in axes[1]:
        ax.set_xlabel("simulated time (periods)")
    for ax in axes[:, 0]:
        ax.set_ylabel("max relative energy error |E(t) − E(0)| / |E(0)|\n"
                      "in log-spaced time bins (20 per decade)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=6, bbox_to_anchor=(0.5, -0.03))
    fig.suptitle("Long-horizon energy error: 32 fixed steps per period (64 for two-body), DOPRI5 "
                 "at rtol 1e-8;\nEuler stops where its error exceeds 10", fontsize=10)
    fig.tight_layout()
    save(fig, directory, "energy_drift", bbox_inches="tight")
