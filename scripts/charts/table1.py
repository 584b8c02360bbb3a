"""Table 1 as a chart: test loss and energy MSE per task, ours against the paper's
(table1_chart), from the table1.json of `hnn reproduce`."""

import os

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, LABELS, MODELS, TASKS, TITLES, PlotError, note, read_json, save

BARS = [("baseline", "ours"), ("baseline", "paper"), ("hnn", "ours"), ("hnn", "paper")]


def read_table1(results):
    path = os.path.join(results, "table1.json")
    if not os.path.isfile(path):
        note("table1.json: missing, Table 1 chart skipped")
        return None
    rows = read_json(path)
    if not isinstance(rows, list) or not all(
            isinstance(r, dict) and "task" in r and "model" in r for r in rows):
        raise PlotError(f"{path}: expected a list of objects with 'task' and 'model' keys")
    numeric = ("train_loss", "train_loss_se", "test_loss", "test_loss_se", "energy_mse",
               "energy_mse_se", "train_seconds", "paper_train_loss", "paper_test_loss",
               "paper_energy_mse")
    for r in rows:
        for key in numeric:
            value = r.get(key)
            if value is not None and not isinstance(value, (int, float)):
                raise PlotError(f"{path}: {r['task']}/{r['model']}: '{key}' is not a number")
    return rows


def table1_index(rows):
    """{(task, model): row} and the tasks in paper order."""
    by_key = {}
    for r in rows:
        if (r["task"], r["model"]) in by_key:
            note(f"table1.json: duplicate entry {r['task']}/{r['model']}, using the last")
        by_key[(r["task"], r["model"])] = r
    tasks = [t for t in TASKS if any((t, m) in by_key for m in MODELS)]
    return by_key, tasks + sorted({r["task"] for r in rows} - set(tasks))


def table1_bar(by_key, tasks, metric, model, source):
    """Bar heights and [lower, upper] standard-error bars (ours only; the lower bar is cut so
    that it stays above zero on the log axis). Missing or non-positive values are NaN."""
    prefix = "paper_" if source == "paper" else ""
    heights, lower, upper = [], [], []
    for task in tasks:
        r = by_key.get((task, model), {})
        v = r.get(prefix + metric)
        ok = isinstance(v, (int, float)) and v > 0
        se = r.get(metric + "_se") if source == "ours" and ok else None
        se = se if isinstance(se, (int, float)) else 0.0
        heights.append(v if ok else np.nan)
        lower.append(min(se, 0.9 * v) if ok else 0.0)
        upper.append(se)
    return np.array(heights), [lower, upper]


def headroom(heights):
    """The factor above the tallest bar that its vertical label needs: a fixed share of the
    log axis, at least 3 decades. (A flat 1e3 clipped the three-body baseline's 3.7e+07 on the
    energy panel, whose bars span 13 decades.)"""
    decades = np.log10(heights.max()) - np.log10(heights.min() / 5)
    return 10 ** max(3.0, 0.3 * decades)


def draw_table1_chart(results, rows):
    """Grouped log bars per task: ours (solid, standard-error bars) vs the paper (hatched, light),
    baseline and HNN; one panel for test loss, one for energy MSE."""
    by_key, tasks = table1_index(rows)
    if not tasks:
        note("table1.json: no rows, Table 1 chart skipped")
        return []
    fig, axes = plt.subplots(1, 2, figsize=(max(10, 2.6 * len(tasks) + 2), 4.8),
                             layout="constrained")
    x, width = np.arange(len(tasks)), 0.2
    for ax, (metric, label) in zip(axes, (("test_loss", "test loss (MSE of dx/dt)"
                                           + ("; pixels: ae+cc+0.1hnn" if "pixel-pendulum"
                                              in tasks else "")),
                                          ("energy_mse", "energy MSE"))):
        tops = []
        for i, (model, source) in enumerate(BARS):
            heights, err = table1_bar(by_key, tasks, metric, model, source)
            paper = source == "paper"
            bars = ax.bar(x + (i - 1.5) * width, heights, width, log=True,
                          yerr=None if paper else err, capsize=2, color=COLORS[model],
                          alpha=0.4 if paper else 0.95, hatch="//" if paper else None,
                          edgecolor="white", label=f"{LABELS[model]} ({source})")
            ax.bar_label(bars, labels=["" if np.isnan(h) else f"{h:.1e}" for h in heights],
                         rotation=90, fontsize=6, padding=2 if paper else 7)
            tops.append(heights)
        finite = np.concatenate(tops)
        finite = finite[np.isfinite(finite)]
        if finite.size:  # room above the tallest bar for its label and the legend
            ax.set_ylim(finite.min() / 5, finite.max() * headroom(finite))
        ax.set_xticks(x, [TITLES.get(t, t) for t in tasks])
        ax.set(title=f"{label}: ours vs the paper's Table 1", ylabel=f"{label}, log scale")
        ax.grid(axis="y", which="major", alpha=0.3)
        ax.legend(ncols=2, loc="upper right", fontsize=7)
    return save(fig, results, "table1_chart")
