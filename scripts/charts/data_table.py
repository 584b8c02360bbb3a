"""The data task's results (docs/data_results.md): mean and standard error over seeds of each
system's metrics, the HNN/baseline energy ratio, R^2 of the copies in other units (results.md),
and Figure 2 of each system's seed-0 pair (charts/NAME/fig2_data), from the sweep of
sweeps/data_results.yaml over the files scripts/data_results.sh makes."""

import os

from . import paper
from .common import write_text
from .sweep_table import cell, finished, mean_se, value

KEYS = ["test_loss", "test_r2", "energy_mse", "coordinate_mse", "valid_prediction_time"]
# The real pendulum's two files as the data task reads them (scripts/data_results.sh).
FILES = {"real_pend_forward": "real-pendulum-data", "real_pend_h_1": "real-pendulum-central"}
COPIES = ("x100", "x0.01")  # the copies of a simulated file in other units
FIGURES = ["nonseparable", "henon-heiles", "double-well", "real-pendulum-central"]


def system_of(r):
    """(system, group) of a run: the task, or the data file's name; the group is the model, or
    hnn-xF for a copy of the data multiplied by F."""
    if r["task"] != "data":
        return r["task"], r["model"]
    stem = os.path.splitext(os.path.basename(r["data"]))[0]
    for copy in COPIES:
        if stem.endswith("-" + copy):
            return stem[:-len(copy) - 1], f"{r['model']}-{copy}"
    return FILES.get(stem, stem), r["model"]


def table(runs):
    """results.md's text from {system: {group: [row]}}."""
    lines = ["| system | model | " + " | ".join(KEYS) + " |",
             "| --- | --- | " + " | ".join("---" for _ in KEYS) + " |"]
    ratios = []
    for system in sorted(runs):
        energy = {}
        for model in ("hnn", "baseline"):
            seeds = runs[system].get(model, [])
            if not seeds:
                continue
            energy[model] = mean_se([value(r, "energy_mse") for r in seeds])[0]
            lines.append(f"| {system} | {model} ({len(seeds)} seeds) | "
                         + " | ".join(cell([value(r, k) for r in seeds]) for k in KEYS) + " |")
        if "hnn" in energy and "baseline" in energy:
            ratios.append((system, energy["baseline"] / energy["hnn"]))
    lines += ["", "| system | baseline energy MSE / HNN energy MSE |", "| --- | --- |"]
    lines += [f"| {name} | {ratio:.3g} |" for name, ratio in ratios]
    lines += ["", "| system | HNN test R² (seed 0) | x100 | x0.01 |", "| --- | --- | --- | --- |"]
    for system in sorted(s for s in runs if "hnn-x100" in runs[s]):
        seed0 = [r for r in runs[system]["hnn"] if r.get("seed", "") in ("", "0")]
        r2 = [value(group[0], "test_r2") for group in
              (seed0, runs[system]["hnn-x100"], runs[system]["hnn-x0.01"])]
        lines.append(f"| {system} | " + " | ".join(f"{v:.6f}" for v in r2) + " |")
    return "\n".join(lines) + "\n"


def draw(rows, sweep, out):
    """results.md and the Figure 2 of each system of FIGURES into OUT."""
    runs = {}
    for r in finished(rows):
        system, group = system_of(r)
        runs.setdefault(system, {}).setdefault(group, []).append(r)
    written = [write_text(os.path.join(out, "results.md"), table(runs))]
    print(written[0])
    for system in FIGURES:
        pair = [r for model in ("hnn", "baseline") for r in runs.get(system, {}).get(model, [])
                if r.get("seed", "") in ("", "0")]
        if pair:
            written += paper.plot_runs([os.path.join(sweep, "runs", r["run"]) for r in pair],
                                       os.path.join(out, "charts", system))
    return written
