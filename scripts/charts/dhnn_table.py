"""The dissipative HNN beside the D-HNN paper's numbers (docs/families.md): per task and model,
mean and standard error over seeds, each with the peer's figure (results.md), from the sweep of
sweeps/dhnn.yaml."""

import os

from .common import write_text
from .sweep_table import cell, finished, value

PEERS = {  # the D-HNN paper's analysis notebooks (one seed each)
    ("damped-spring", "dhnn"): {"test_loss": 5.75e-5, "dhnn_paper_state_mse": 3.6e-6},
    ("damped-spring", "baseline"): {"test_loss": 9.86e-5, "dhnn_paper_state_mse": 6.0e-6},
    ("damped-spring", "hnn"): {"test_loss": 0.626, "dhnn_paper_state_mse": 0.29},
    ("real-pendulum", "dhnn"): {"test_loss": 9.46e-4, "held_out_energy_mse": 1.068e-3},
    ("real-pendulum", "baseline"): {"test_loss": 1.11e-3, "held_out_energy_mse": 1.167e-3},
    ("real-pendulum", "hnn"): {"test_loss": 1.40e-3, "held_out_energy_mse": 1.018e-2},
}
KEYS = {"damped-spring": ["test_loss", "dhnn_paper_state_mse", "dissipation_share",
                          "train_seconds"],
        "real-pendulum": ["test_loss", "held_out_energy_mse", "energy_mse",
                          "valid_prediction_time", "dissipation_share", "train_seconds"]}


def study_of(r):
    """The damped spring is its task; the real pendulum is the data task on its measurements."""
    return "real-pendulum" if r["task"] == "data" else r["task"]


def table(rows):
    lines = []
    for task, names in KEYS.items():
        lines += [f"### {task}", "", "| model | " + " | ".join(names) + " |",
                  "| --- | " + " | ".join("---" for _ in names) + " |"]
        for model in ("dhnn", "baseline", "hnn"):
            runs = [r for r in rows if study_of(r) == task and r["model"] == model]
            cells = []
            for k in names:
                peer = PEERS.get((task, model), {}).get(k)
                cells.append(cell([value(r, k) for r in runs])
                             + (f" (peer {peer:.3g})" if peer is not None else ""))
            lines.append(f"| {model} ({len(runs)} seeds) | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines) + "\n"


def draw(rows, sweep, out):
    """OUT/results.md."""
    path = write_text(os.path.join(out, "results.md"), table(finished(rows)))
    print(path)
    return [path]
