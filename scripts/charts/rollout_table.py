"""Training through an integrator (docs/families.md): the SRNN paper's three-body setup and the
coarsely sampled spring, pendulum and real pendulum, rollout loss against dx/dt targets, mean and
standard error over seeds (results.md), from the sweep of sweeps/rollout.yaml."""

import os

from .common import write_text
from . import sweep_table
from .sweep_table import mean_se, settings, value

LABELS = {"derivative": "HNN, dx/dt targets (dopri5 rollout)",
          "leapfrog": "HNN, rollout loss through leapfrog (horizon 4)",
          "midpoint": "HNN, rollout loss through the implicit midpoint (horizon 4)"}
COARSE = ["spring-dt0.5", "spring-dt1.0", "pendulum-dt0.5", "pendulum-dt1.0", "real-pendulum"]


def data_of(r):
    """The data a run learned: its task, with the sampling step when the spec sets one."""
    dt = settings(r).get("sample_dt")
    return r["task"] if dt is None else f"{r['task']}-dt{float(dt)}"


def kind_of(r):
    """derivative (dx/dt targets), or the integrator the rollout loss goes through."""
    return "derivative" if r.get("loss", "") in ("", "derivative") else r["integrator"]


def cell(values, digits=3, failed=0):
    """'mean ± se' over seeds with the count of failed runs; 'failed' or 'n/a' without one."""
    if mean_se(values)[2] == 0:
        return "failed" if failed else "n/a"
    return sweep_table.cell(values, digits) + (f" ({failed} failed)" if failed else "")


def table(rows):
    def runs(data, kind, status="done"):
        return [r for r in rows if data_of(r) == data and kind_of(r) == kind
                and r["status"] == status]

    def values(runs, key):
        return [value(r, key) for r in runs]

    lines = ["## Three-body at dt = 1 (the SRNN paper's setup)", "",
             "L2 position error: per test trajectory (32), the Euclidean distance of each body's "
             "predicted position to the true one, averaged over the 3 bodies and the 10 sampled "
             "times (t = 0..9); mean over the seeds ± standard error, and the mean over seeds of "
             "the spread (std) over trajectories. SRNN's figures: SRNN 0.26 ± 0.07, true "
             "equations by leapfrog 0.47 ± 0.18, one-step HNN 1.64.", "",
             "| model | seeds | position error | std over trajectories | on training "
             "trajectories | state MSE | train s |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for kind, label in LABELS.items():
        r = runs("three-body", kind)
        lines.append(f"| {label} | {len(r)} | {cell(values(r, 'stretch_position_error'))} | "
                     f"{cell(values(r, 'stretch_position_error_std'), 2)} | "
                     f"{cell(values(r, 'train_stretch_position_error'))} | "
                     f"{cell(values(r, 'stretch_state_mse'))} | "
                     f"{cell(values(r, 'train_seconds'), 2)} |")
    r = runs("three-body", "derivative")
    lines += [f"| true equations by leapfrog, dt = 1 | {len(r)} data seeds | "
              f"{cell(values(r, 'truth_leapfrog_position_error'))} | "
              f"{cell(values(r, 'truth_leapfrog_position_error_std'), 2)} | | "
              f"{cell(values(r, 'truth_leapfrog_state_mse'))} | |", "",
              "## Coarse, noisy samples: rollout loss against dx/dt targets on the same data", "",
              "Held-out error along the test trajectories from their first (noisy) state: state "
              "MSE over every later sample, mean over seeds ± standard error. Rollout models step "
              "as they trained (one step per interval); derivative models are integrated by "
              "dopri5.", "",
              "| data | derivative | rollout, leapfrog | truth by leapfrog |",
              "| --- | --- | --- | --- |"]
    for data in COARSE:
        cells = [cell(values(runs(data, k), "stretch_state_mse"),
                      failed=len(runs(data, k, "failed"))) for k in ("derivative", "leapfrog")]
        cells.append(cell(values(runs(data, "derivative"), "truth_leapfrog_state_mse")))
        lines.append(f"| {data} | " + " | ".join(cells) + " |")
    failed = [r for r in rows if r["status"] == "failed"]
    if failed:
        lines += ["", "Failed runs:", ""] + [f"- {r['run']}: {r['reason']}" for r in failed]
    return "\n".join(lines) + "\n"


def draw(rows, sweep, out):
    """OUT/results.md."""
    path = write_text(os.path.join(out, "results.md"), table(rows))
    print(path)
    return [path]
