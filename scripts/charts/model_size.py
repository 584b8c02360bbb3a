"""Chart 4 of docs/speed_accuracy.md: model size, hidden width (depth 2) and depth against
training time, test loss and energy MSE, with the paper's 200-200 and the chosen lean model
(model_size), from the model-size sweep's results.csv (sweeps/model_size.yaml)."""

import matplotlib.pyplot as plt
from matplotlib import ticker

from .common import SHORT_TITLES as TITLES
from .common import SIZE_COLORS as MODEL_COLOR
from .common import present, save
from .lean import PAPER, config_stats, write_lean
from .sweep_table import num


def plot_model_size(rows, directory):
    stats = config_stats(rows)
    # Tasks with a width sweep (the pixel pendulum has only its paper run: 10 minutes a run).
    tasks = [t for t in present(rows)
             if len({r["hidden"] for r in rows if r["task"] == t and r["model"] == "hnn"}) > 1]
    chosen = write_lean(stats, tasks, directory)
    metrics = [("train_seconds", "training time (s, wall, 1 thread)"),
               ("test_loss", "final test loss (MSE of dx/dt)"),
               ("energy_mse", "energy MSE along rollouts")]
    fig, axes = plt.subplots(len(metrics), len(tasks), figsize=(3.3 * len(tasks), 9.2),
                             squeeze=False)
    seed0 = [r for r in rows if r["dtype"] == "double" and r["seed"] == "0"]
    for col, task in enumerate(tasks):
        paper = stats[(task, "hnn", PAPER)]
        for row, (metric, label) in enumerate(metrics):
            ax = axes[row, col]
            for model, ls in [("hnn", "-"), ("baseline", "--")]:
                color = MODEL_COLOR[model]
                width = sorted((num(r, "params"), r) for r in seed0 if r["task"] == task
                               and r["model"] == model and r["depth"] == "2")
                if width:
                    ax.plot([p for p, _ in width], [num(r, metric) for _, r in width], ls=ls,
                            marker="o", ms=4, color=color, lw=1.2)
                    if row == 0 and model == "hnn":
                        for p, r in width:
                            ax.annotate(r["width"], (p, num(r, metric)), fontsize=6.5,
                                        textcoords="offset points", xytext=(-3, 5))
                depth_width = {int(r["width"]) for r in seed0 if r["task"] == task
                               and r["model"] == model and r["depth"] != "2"}
                for dw in depth_width:
                    depth = sorted((num(r, "params"), r) for r in seed0 if r["task"] == task
                                   and r["model"] == model and int(r["width"]) == dw)
                    ax.plot([p for p, _ in depth], [num(r, metric) for _, r in depth], ls=":",
                            lw=1, color=color)
                    for p, r in depth:
                        ax.plot([p], [num(r, metric)], ls="none", ms=6, color=color,
                                marker={"1": "v", "2": "D", "3": "^"}[r["depth"]], mfc="white")
            if metric != "train_seconds":  # the paper config's noise band (2 se)
                m, se, _ = paper[metric]
                ax.axhspan(max(m - 2 * se, m * 1e-3), m + 2 * se, color="tab:blue", alpha=0.12,
                           lw=0)
            # Extra seeds, and the chosen lean model.
            for (t, mo, h), s in stats.items():
                if t == task and mo == "hnn" and s["n"] > 1:
                    for r in rows:
                        if (r["task"] == task and r["model"] == "hnn" and r["hidden"] == h
                                and r["dtype"] == "double" and r["seed"] != "0"):
                            ax.plot([s["params"]], [num(r, metric)], ls="none", marker=".",
                                    color="tab:blue", ms=4, alpha=0.7)
            if task in chosen:
                s = stats[(task, "hnn", chosen[task])]
                ax.plot([s["params"]], [s[metric][0]], ls="none", marker="o", ms=13, mfc="none",
                        mec="tab:green", mew=2)
            ax.plot([paper["params"]], [paper[metric][0]], ls="none", marker="*", ms=12,
                    color="tab:red", zorder=5)
            ax.set(xscale="log", yscale="log")
            ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:,.0f}"))
            ax.xaxis.set_minor_formatter(ticker.NullFormatter())
            if row == 0:
                ax.set_title(TITLES[task])
            if row == len(metrics) - 1:
                ax.set_xlabel("parameters")
            if col == 0:
                ax.set_ylabel(label)
    handles = [
        plt.Line2D([], [], color="tab:blue", marker="o", ms=4, label="HNN, depth 2, width 16-256"),
        plt.Line2D([], [], color="tab:orange", ls="--", marker="o", ms=4,
                   label="baseline, depth 2"),
        plt.Line2D([], [], color="tab:blue", ls=":", marker="v", mfc="white", ms=6,
                   label="depth 1 / 3 (▽ / △) at fixed width"),
        plt.Line2D([], [], color="tab:blue", ls="none", marker=".", ms=5, label="seeds 1, 2"),
        plt.Line2D([], [], color="tab:red", ls="none", marker="*", ms=11,
                   label="paper 200-200 (mean over seeds)"),
        plt.Rectangle((0, 0), 1, 1, color="tab:blue", alpha=0.12, label="paper ± 2 se"),
        plt.Line2D([], [], ls="none", marker="o", ms=11, mfc="none", mec="tab:green", mew=2,
                   label="chosen lean (mean over seeds)"),
    ]
    if not any(r["model"] == "baseline" for r in seed0 if r["depth"] == "2"
               and r["hidden"] != PAPER):
        handles.pop(1)
    fig.legend(handles=handles, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.06))
    fig.suptitle("Model size: a model no more than the scene needs (double, paper's steps; "
                 "seed 0 lines)", fontsize=10)
    fig.tight_layout()
    save(fig, directory, "model_size", bbox_inches="tight")
