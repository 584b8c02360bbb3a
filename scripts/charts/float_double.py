"""Chart 3 of docs/speed_accuracy.md: float against double, training time against final test
loss and energy MSE at the paper's settings (float_double), from the model-size sweep's
results.csv (sweeps/model_size.yaml)."""

import matplotlib.pyplot as plt
from matplotlib import ticker

from .common import SHORT_TITLES as TITLES
from .common import SIZE_COLORS as MODEL_COLOR
from .common import SIZE_LABELS as MODEL_LABEL
from .common import present, save
from .sweep_table import num

DTYPE_MARKER = {"float": dict(marker="o", mfc="white", ms=7), "double": dict(marker="s", ms=6)}


def plain_log_ticks(axis):
    """A few round ticks written as plain numbers on a log axis that spans about a decade
    (training times): matplotlib's own labels crowd there ('3x10^0 4x10^0')."""
    axis.set_major_locator(ticker.MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]))
    axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(ticker.NullFormatter())



def plot_float_double(rows, directory):
    tasks = present(rows)
    fig, axes = plt.subplots(2, len(tasks), figsize=(3.3 * len(tasks), 6.6), squeeze=False)
    for col, task in enumerate(tasks):
        for row, (metric, label) in enumerate([("test_loss", "final test loss (MSE of dx/dt)"),
                                               ("energy_mse", "energy MSE along rollouts")]):
            ax = axes[row, col]
            for model in ["hnn", "baseline"]:
                pts = {r["dtype"]: r for r in rows if r["task"] == task and r["model"] == model}
                if not pts:
                    continue
                order = [d for d in ["float", "double"] if d in pts]
                xs = [num(pts[d], "train_seconds") for d in order]
                ys = [num(pts[d], metric) for d in order]
                ax.plot(xs, ys, color=MODEL_COLOR[model], lw=0.8, alpha=0.6)
                for d, x, y in zip(order, xs, ys):
                    ax.errorbar([x], [y], yerr=[[0], [num(pts[d], metric + "_se")]],
                                color=MODEL_COLOR[model], capsize=2, lw=1, ls="none",
                                **DTYPE_MARKER[d])
            ax.set(xscale="log", yscale="log")
            plain_log_ticks(ax.xaxis)
            if row == 0:
                ax.set_title(TITLES[task])
            if row == 1:
                ax.set_xlabel("training time (s, wall, 1 thread)")
            if col == 0:
                ax.set_ylabel(label)
    handles = [plt.Line2D([], [], color=MODEL_COLOR[m], lw=2, label=MODEL_LABEL[m])
               for m in ["hnn", "baseline"]]
    handles += [plt.Line2D([], [], color="gray", ls="none", label=f"{d}", **DTYPE_MARKER[d])
                for d in ["float", "double"]]
    fig.legend(handles=handles, loc="lower center", ncol=4, bbox_to_anchor=(0.5, -0.04))
    fig.suptitle("float vs double: training time against accuracy, paper settings (200-200, "
                 "paper's steps, seed 0); error bars +1 standard error",
                 fontsize=10)
    fig.tight_layout()
    save(fig, directory, "float_double", bbox_inches="tight")
