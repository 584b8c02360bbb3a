"""The lean model of each task (the `lean` preset, docs/speed_accuracy.md section 4): the
smallest HNN within the noise of the paper's 200-200 over seeds, written as lean.csv.

The lean model of a task is the HNN with the fewest parameters whose mean test loss and mean
energy MSE are both at most the paper config's mean + 2 * sqrt(se_candidate^2 + se_paper^2)
(better is always within the noise), and at most MAX_RATIO times it. A config's se combines
the runs' own standard errors (over test points, or over rollouts) with the spread between its
seeds:
  se^2 = mean(se_i^2) / n + var_seeds / n     (var_seeds = 0 for one seed).
Only configs with at least MIN_SEEDS seeds are chosen (when any has them)."""

import csv
import io
import math
import os
from collections import defaultdict

from .common import write_text
from .sweep_table import num

PAPER = "200-200"
MIN_SEEDS = 2
MAX_RATIO = 2.0


def config_stats(rows):
    """{(task, model, hidden): {metric: (mean, se, n), params, n, depth, width}} over the seeds
    of the double runs (rows of charts/sweep_table.py's with_sizes)."""
    groups = defaultdict(list)
    for r in rows:
        if r["dtype"] == "double":
            groups[(r["task"], r["model"], r["hidden"])].append(r)
    stats = {}
    for key, runs in groups.items():
        s = {"params": int(num(runs[0], "params")), "n": len(runs),
             "depth": int(num(runs[0], "depth")), "width": int(num(runs[0], "width"))}
        for metric in ["test_loss", "energy_mse", "train_seconds"]:
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
    """(hidden, its stats) of the task's lean model; (None, None) without a paper config."""
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
    """DIRECTORY/lean.csv: per task, the paper's 200-200 and the lean model, means over seeds and
    the wall-time speed-up; returns {task: the lean model's hidden widths}."""
    path = os.path.join(directory, "lean.csv")
    fields = ["task", "config", "hidden", "params", "seeds", "train_seconds", "speedup_wall",
              "test_loss", "test_loss_se", "energy_mse", "energy_mse_se"]
    chosen = {}
    text = io.StringIO()
    w = csv.DictWriter(text, fieldnames=fields, lineterminator="\n")
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
                "speedup_wall": f"{paper['train_seconds'][0] / s['train_seconds'][0]:.3g}",
                "test_loss": f"{s['test_loss'][0]:.5g}", "test_loss_se": f"{s['test_loss'][1]:.2g}",
                "energy_mse": f"{s['energy_mse'][0]:.5g}",
                "energy_mse_se": f"{s['energy_mse'][1]:.2g}"})
    print(write_text(path, text.getvalue()))
    return chosen
