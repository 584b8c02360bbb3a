"""Reversibility: the return distance after integrating forward then backward, per integrator,
and the flow map's |log det|, for every run of reversibility.json (reversibility)."""

import os

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, PlotError, note, read_json, save


def draw_reversibility(results):
    path = os.path.join(results, "reversibility.json")
    if not os.path.isfile(path):
        note("reversibility.json: missing (run `hnn reversibility --report`), chart skipped")
        return []
    rows = read_json(path)
    if not isinstance(rows, list):
        raise PlotError(f"{path}: expected a list of runs")
    integrators = ["midpoint", "rk4", "dopri5"]
    labels = [f"{r.get('task')}\n{r.get('model')}" for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.0), gridspec_kw={"width_ratios": [3, 1.3]})
    width = 0.8 / len(integrators)
    for j, name in enumerate(integrators):
        values = []
        for r in rows:
            found = [i for i in r.get("integrators", []) if i.get("integrator") == name]
            v = found[0].get("return_distance_mean") if found else None
            values.append(v if isinstance(v, (int, float)) and v > 0 else np.nan)
        axes[0].bar(np.arange(len(rows)) + (j - 1) * width, values, width, label=name)
    axes[0].set_yscale("log")
    axes[0].set_xticks(np.arange(len(rows)))
    axes[0].set_xticklabels(labels, fontsize=7)
    axes[0].set(title="Forward then backward: mean return distance", ylabel="|x_back - x0|")
    axes[0].legend(loc="best")
    dets = [r.get("volume", {}).get("abs_log_det_mean") for r in rows]
    dets = [d if isinstance(d, (int, float)) and d > 0 else np.nan for d in dets]
    colors = [COLORS.get(r.get("model"), "0.5") for r in rows]
    axes[1].barh(np.arange(len(rows)), dets, color=colors)
    axes[1].set_xscale("log")
    axes[1].set_yticks(np.arange(len(rows)))
    axes[1].set_yticklabels([lbl.replace("\n", " ") for lbl in labels], fontsize=7)
    axes[1].invert_yaxis()
    axes[1].set(title="|log det| of the flow map (0 = volume kept)")
    fig.tight_layout()
    return save(fig, results, "reversibility")
