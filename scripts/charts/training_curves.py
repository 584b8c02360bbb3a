"""Training curves: train and test loss against the step, one panel per task
(training_curves)."""

import math

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, LABELS, MODELS, TITLES, note, save
from .rollout import log_y_if_positive

def draw_training_curves(results, all_runs, title=None):
    """One panel per task: train (solid) and test (dashed) loss vs step, baseline and HNN.
    title: the panel's title instead of the task's (run folders of the data task)."""
    tasks = [t for t, runs in all_runs.items()
             if any(runs.get(m) and runs[m]["loss"] is not None for m in MODELS)]
    if not tasks:
        note("no loss_curve.csv found, training curves skipped")
        return []
    cols = min(3, len(tasks))
    rows = math.ceil(len(tasks) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.6 * rows), layout="constrained",
                             squeeze=False)
    for ax, task in zip(axes.flat, tasks):
        curves = []
        for model in MODELS:
            loss = (all_runs[task].get(model) or {}).get("loss")
            if loss is None:
                continue
            for split, style in (("train", "-"), ("test", "--")):
                y = loss[f"{split}_loss"]
                ok = np.isfinite(y)
                ax.plot(loss["step"][ok], y[ok], style, color=COLORS[model],
                        label=f"{LABELS[model]}, {split}")
                curves.append(y)
        log_y_if_positive(ax, *curves)
        # A data run's loss_curve.csv is in standardised units: its columns say so (older
        # files only through metrics.json's "units", so the data task's label says it too).
        standardised = task == "data" or any(
            ((all_runs[task].get(m) or {}).get("loss") or {}).get("units") == "standardised"
            for m in MODELS)
        ylabel = ("loss: ae + cc + 0.1 hnn" if task == "pixel-pendulum" else
                  "loss: MSE of dx/dt (standardised units)" if standardised else
                  "loss: MSE of dx/dt")
        ax.set(title=title or TITLES.get(task, task), xlabel="training step", ylabel=ylabel)
        ax.legend()
    for ax in list(axes.flat)[len(tasks):]:
        ax.set_visible(False)
    fig.suptitle("Training curves: train (solid) and test (dashed) loss")
    return save(fig, results, "training_curves")


TABLE1_BARS = [("baseline", "ours"), ("baseline", "paper"), ("hnn", "ours"), ("hnn", "paper")]
