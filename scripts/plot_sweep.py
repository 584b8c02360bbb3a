#!/usr/bin/python3
"""Charts 3 and 4 of issue 7 from the CSV files of scripts/sweep.py, and the lean choice.

Usage: /usr/bin/python3 scripts/plot_sweep.py [SWEEP_DIR] [CHART_DIR]
       (defaults: results/sweep and docs/charts)

Reads SWEEP_DIR/float_double.csv and SWEEP_DIR/model_size.csv, copies them into CHART_DIR, and
writes there, each chart as PNG and SVG:
  float_double   training time against final test loss and energy MSE, float and double
  model_size     hidden width (depth 2) and depth against training time, test loss, energy MSE
  lean.csv       per task: the paper's 200-200 and the chosen lean model, averaged over seeds

The lean model of a task is the HNN with the fewest parameters whose mean test loss and mean
energy MSE are both at most the paper config's mean + 2 * sqrt(se_candidate^2 + se_paper^2)
(better is always within the noise), and at most MAX_RATIO times it. A config's se combines
the runs' own standard errors (over test points, or over rollouts) with the spread between its
seeds:
  se^2 = mean(se_i^2) / n + var_seeds / n     (var_seeds = 0 for one seed).
Only configs with at least MIN_SEEDS seeds are chosen (when any has them).
"""

import csv
import math
import os
import shutil
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot  # noqa: E402  (the atomic PNG+SVG writer)
from matplotlib import ticker  # noqa: E402

plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "hnn", "font.size": 9,
                     "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 8})

TASKS = ["spring", "pendulum", "real-pendulum", "two-body", "three-body", "pixel-pendulum"]
TITLES = {"spring": "Mass-spring", "pendulum": "Pendulum", "real-pendulum": "Real pendulum",
          "two-body": "Two-body", "three-body": "Three-body", "pixel-pendulum": "Pixel pendulum"}
MODEL_COLOR = {"hnn": "tab:blue", "baseline": "tab:orange"}
MODEL_LABEL = {"hnn": "HNN", "baseline": "baseline"}
DTYPE_MARKER = {"float": dict(marker="o", mfc="white", ms=7), "double": dict(marker="s", ms=6)}
PAPER = "200-200"
MIN_SEEDS = 2
MAX_RATIO = 2.0


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(r, key):
    v = r.get(key, "")
    return float(v) if v not in ("", None) else math.nan


def save(fig, directory, name):
    plot.save(fig, directory, name, bbox_inches="tight")


def plain_log_ticks(axis):
    """A few round ticks written as plain numbers on a log axis that spans about a decade
    (training times): matplotlib's own labels crowd there ('3x10^0 4x10^0')."""
    axis.set_major_locator(ticker.MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]))
    axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(ticker.NullFormatter())


def present(rows):
    return [t for t in TASKS if any(r["task"] == t for r in rows)]


def load_note(rows):
    loads = [num(r, "load1") for r in rows if not math.isnan(num(r, "load1"))]
    if not loads:
        return ""
    return f"1-min load average at the runs' starts {min(loads):.1f} to {max(loads):.1f} on 2 cores"


# ---------------------------------------------------------------------------- chart 3

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
                 "paper's steps, seed 0); error bars +1 standard error\n" + load_note(rows),
                 fontsize=10)
    fig.tight_layout()
    save(fig, directory, "float_double")


# ---------------------------------------------------------------------------- chart 4 and lean

def config_stats(rows):
    """{(task, model, hidden): {metric: (mean, se, n), params, seconds}} over seeds (double)."""
    groups = defaultdict(list)
    for r in rows:
        if r["dtype"] == "double":
            groups[(r["task"], r["model"], r["hidden"])].append(r)
    stats = {}
    for key, runs in groups.items():
        s = {"params": int(num(runs[0], "params")), "n": len(runs),
             "depth": int(num(runs[0], "depth")), "width": int(num(runs[0], "width"))}
        for metric in ["test_loss", "energy_mse", "train_seconds", "cpu_seconds"]:
            vals = [num(r, metric) for r in runs]
            n = len(vals)
            mean = sum(vals) / n
            ses = [num(r, metric + "_se") for r in runs]
            within = sum(0 if math.isnan(e) else e * e for e in ses) / n
            between = sum((v - mean) ** 2 for v in vals) / (n - 1) if n > 1 else 0.0
            s[metric] = (mean, math.sqrt((within + between) / n), n)
        stats[key] = s
    return stats


def within_noise(cand, paper, metric):
    """Within the noise, and at most MAX_RATIO times the paper's mean: where the noise is as
    large as the metric itself (three-body's chaotic rollouts) the first test alone passes
    anything."""
    (m, se, _), (mp, sep, _) = cand[metric], paper[metric]
    return m <= mp + 2 * math.hypot(se, sep) and m <= MAX_RATIO * mp


def choose_lean(stats, task, model="hnn"):
    paper = stats.get((task, model, PAPER))
    if paper is None:
        return None, None
    configs = [(s["params"], h, s) for (t, m, h), s in stats.items() if t == task and m == model]
    seeded = [c for c in configs if c[2]["n"] >= MIN_SEEDS]
    pool = seeded if len(seeded) > 1 else configs
    for _, hidden, s in sorted(pool):
        if all(within_noise(s, paper, m) for m in ["test_loss", "energy_mse"]):
            return hidden, s
    return PAPER, paper


def write_lean(stats, tasks, directory):
    path = os.path.join(directory, "lean.csv")
    fields = ["task", "config", "hidden", "params", "seeds", "train_seconds", "cpu_seconds",
              "speedup_wall", "speedup_cpu", "test_loss", "test_loss_se", "energy_mse",
              "energy_mse_se"]
    chosen = {}
    with open(path + ".tmp", "w", newline="") as f:  # renamed when complete
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for task in tasks:
            hidden, lean = choose_lean(stats, task)
            if hidden is None:
                continue
            chosen[task] = hidden
            paper = stats[(task, "hnn", PAPER)]
            for name, h, s in [("paper", PAPER, paper), ("lean", hidden, lean)]:
                w.writerow({
                    "task": task, "config": name, "hidden": h, "params": s["params"],
                    "seeds": s["n"], "train_seconds": f"{s['train_seconds'][0]:.4g}",
                    "cpu_seconds": f"{s['cpu_seconds'][0]:.4g}",
                    "speedup_wall": f"{paper['train_seconds'][0] / s['train_seconds'][0]:.3g}",
                    "speedup_cpu": f"{paper['cpu_seconds'][0] / s['cpu_seconds'][0]:.3g}",
                    "test_loss": f"{s['test_loss'][0]:.5g}", "test_loss_se": f"{s['test_loss'][1]:.2g}",
                    "energy_mse": f"{s['energy_mse'][0]:.5g}",
                    "energy_mse_se": f"{s['energy_mse'][1]:.2g}"})
    os.replace(path + ".tmp", path)
    print(path)
    return chosen


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
                 "seed 0 lines)\n" + load_note(rows), fontsize=10)
    fig.tight_layout()
    save(fig, directory, "model_size")


def main():
    sweep = sys.argv[1] if len(sys.argv) > 1 else "results/sweep"
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/charts"
    os.makedirs(out, exist_ok=True)
    for name, draw in [("float_double", plot_float_double), ("model_size", plot_model_size)]:
        path = os.path.join(sweep, name + ".csv")
        if not os.path.exists(path):
            print(f"plot_sweep: no {path}, skipping {name}", file=sys.stderr)
            continue
        if os.path.abspath(os.path.dirname(path)) != os.path.abspath(out):
            copy = os.path.join(out, name + ".csv")
            shutil.copy(path, copy + ".tmp")
            os.replace(copy + ".tmp", copy)
        draw(read_csv(path), out)


if __name__ == "__main__":
    main()
