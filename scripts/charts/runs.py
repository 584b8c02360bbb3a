"""The charts of `hnn train` run folders (scripts/plot.py --runs) and of any rollout CSV that hnn
writes (--rollouts): Figure 2 of the runs' test rollouts, their loss curves, the learned H
against the true one over the phase plane, and Figure 2 of each `hnn rollout` file."""

import glob
import os

import numpy as np

from . import fig2, h_contour, h_slice, training_curves
from .common import MODELS, PIXEL_TASK, TITLES, PlotError, note, read_json, read_loss_curve
from .rollout import Rollout, rollouts_of, setting


def read_metrics(path):
    metrics = read_json(path)
    if not isinstance(metrics, dict):
        raise PlotError(f"{path}: expected a JSON object")
    return metrics


def load_run(folder):
    """{'folder', 'task', 'model', 'metrics', 'loss', 'rollout', 'paths'} of one `hnn train` run
    folder: metrics.json and rollout.csv must be there; loss_curve.csv is read when present;
    'paths' are its `hnn rollout` files, rollout_<integrator>.csv, by name."""
    if not os.path.isdir(folder):
        raise PlotError(f"{folder}: not a folder")
    run = {"folder": folder}
    for key, name, reader in (("metrics", "metrics.json", read_metrics),
                              ("rollout", "rollout.csv", Rollout)):
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            raise PlotError(f"{path}: missing (is {folder} a finished run folder?)")
        run[key] = reader(path)
    for key in ("task", "model"):
        value = setting(run["metrics"], key)
        if not isinstance(value, str) or not value:
            raise PlotError(f"{os.path.join(folder, 'metrics.json')}: no '{key}' setting")
        run[key] = value
    if run["model"] not in MODELS:
        raise PlotError(f"{os.path.join(folder, 'metrics.json')}: model '{run['model']}' is not"
                        f" one of {', '.join(MODELS)}")
    loss = os.path.join(folder, "loss_curve.csv")
    run["loss"] = read_loss_curve(loss) if os.path.isfile(loss) else None
    if run["loss"] is None:
        note(f"{loss}: missing, no loss curve for this run")
    run["paths"] = {os.path.basename(p)[:-4]: Rollout(p)
                    for p in sorted(glob.glob(os.path.join(folder, "rollout_*.csv")))}
    return run


def same_trajectories(a, b):
    """Whether two Rollouts hold the same trajectories: the same times and true states."""
    return len(a.trajs) == len(b.trajs) and all(
        len(x["t"]) == len(y["t"]) and np.allclose(x["t"], y["t"], rtol=1e-9, atol=0.0)
        and np.allclose(x["true"], y["true"], rtol=1e-6, atol=1e-9 * max(
            1.0, float(np.nanmax(np.abs(x["true"]), initial=0.0))), equal_nan=True)
        for x, y in zip(a.trajs, b.trajs))


def check_runs(loaded):
    """Raises unless the runs are of one task and the same held-out data, at most one per model:
    the same trajectories at the same times with the same true states."""
    tasks = {run["task"] for run in loaded}
    if len(tasks) > 1:
        raise PlotError("runs of different tasks: " + ", ".join(
            f"{run['folder']} ({run['task']})" for run in loaded))
    by_model = {}
    for run in loaded:
        if run["model"] in by_model:
            raise PlotError(f"two {run['model']} runs: {by_model[run['model']]['folder']} and"
                            f" {run['folder']}; give at most one run per model")
        by_model[run["model"]] = run
    first = loaded[0]
    for run in loaded[1:]:
        if not same_trajectories(first["rollout"], run["rollout"]):
            files = [setting(r["metrics"], "data_file") for r in (first, run)]
            detail = (f" (data files {files[0]!r} and {files[1]!r})" if files[0] != files[1]
                      else "")
            raise PlotError(f"runs of different data: {first['folder']} and {run['folder']} hold"
                            f" different test trajectories in rollout.csv{detail}")
    return by_model


def run_title(task, runs):
    """The figure's title: the task's, or for the data task the data file's name."""
    if task != "data":
        return TITLES.get(task, task)
    files = {setting(r["metrics"], "data_file") for r in runs.values()}
    files = sorted(os.path.basename(f) for f in files if isinstance(f, str) and f)
    return f"Data from {', '.join(files)}" if files else "Data"


def show_longest(rolls):
    """Shows, in every rollout, the trajectory that spans the longest time (the first of those):
    it shows most."""
    trajs = rolls[0].trajs
    show = max(range(len(trajs)), key=lambda k: (trajs[k]["t"][-1] - trajs[k]["t"][0], -k))
    for roll in rolls:
        roll.show = show


def draw_contour(out, task, runs, title, roll, stem=None):
    """The H contour of an HNN's rollouts, with the state's names from metrics.json."""
    metrics = (runs.get("hnn") or {}).get("metrics") or {}
    _, names, _ = fig2.phase_axes(roll.d, metrics)
    return h_contour.draw_h_contour(out, task, roll, names, title, stem=stem)


def draw_slice(out, task, run, title, h_grid=None):
    """The learned H beside the true energy on a 2-D slice (h_slice_<task>) of an HNN run of
    more than one degree of freedom: from the grid CSV h_grid, or from `hnn hamiltonian` run on
    it through its shown test rollout's first state (out/h_grid_<task>.csv)."""
    written = []
    if h_grid is None:
        h_grid = h_slice.make_grid(run["folder"], run["rollout"], out, f"h_grid_{task}")
        if h_grid is None:
            return []
        written.append(h_grid)
    grid = h_slice.read_grid(h_grid)
    roll = run["rollout"]
    _, labels, _ = fig2.phase_axes(roll.d, run["metrics"])
    if grid["names"] != [roll.names[0], roll.names[roll.d // 2]]:
        labels = None  # a grid of other columns (--h-grid): their names alone
    return written + h_slice.draw_h_slice(out, task, grid, title, labels=labels)


def draw_paths(out, task, runs, title):
    """Figure 2 of the runs' `hnn rollout` files, one per file name: both models in one figure
    when their files hold the same trajectories, else one figure each."""
    written = []
    for name in sorted({n for run in runs.values() for n in run["paths"]}):
        having = {m: run for m, run in runs.items() if name in run["paths"]}
        rolls = [run["paths"][name] for run in having.values()]
        together = all(same_trajectories(rolls[0], r) for r in rolls[1:])
        groups = [having] if together else [{m: run} for m, run in having.items()]
        for group in groups:
            view = {m: {"metrics": run["metrics"], "rollout": run["paths"][name],
                        "of_file": True} for m, run in group.items()}
            show_longest([v["rollout"] for v in view.values()])
            stem = f"{name}_{task}" + ("" if together else f"_{next(iter(group))}")
            shown_rolls, truth = rollouts_of(view)
            written += fig2.draw_fig2(out, task, view, shown_rolls, truth,
                                      title=f"{title} (hnn rollout: {name}.csv)", stem=stem)
    return written


def plot_runs(folders, out, h_grid=None):
    """Figure 2 of the given run folders into out/fig2_<task>, their loss curves
    (training_curves), the HNN's learned H against the true one (h_contour_<task> for one
    degree of freedom, else h_slice_<task> from the grid CSV h_grid or `hnn hamiltonian`) and
    Figure 2 of their rollout_<integrator>.csv; returns the files written."""
    loaded = [load_run(folder) for folder in folders]
    runs = check_runs(loaded)
    task = loaded[0]["task"]
    if task == PIXEL_TASK:
        raise PlotError(f"{task}: rollouts of frames; scripts/plot_pixel.py draws them")
    os.makedirs(out, exist_ok=True)
    show_longest([run["rollout"] for run in loaded])
    rolls, truth = rollouts_of(runs)
    title = run_title(task, runs)
    written = fig2.draw_fig2(out, task, runs, rolls, truth, title=title)
    written += training_curves.draw_training_curves(out, {task: runs}, title=title)
    if h_grid is not None and "hnn" not in runs:
        raise PlotError(f"--h-grid {h_grid}: the learned H of which run? give an hnn run")
    if "hnn" in runs and runs["hnn"]["rollout"].d == 2 and h_grid is None:
        written += draw_contour(out, task, runs, title, runs["hnn"]["rollout"])
    elif "hnn" in runs:
        written += draw_slice(out, task, runs["hnn"], title, h_grid)
    return written + draw_paths(out, task, runs, title)


def load_rollout_file(path):
    """{'path', 'task', 'model', 'metrics', 'rollout'} of a rollout CSV; the task, the model and
    the state's names come from the metrics.json beside it (a run folder's), else the model is
    the HNN when the file has learned_h values."""
    if not os.path.isfile(path):
        raise PlotError(f"{path}: no such file")
    roll = Rollout(path)
    beside = os.path.join(os.path.dirname(path) or ".", "metrics.json")
    metrics = read_metrics(beside) if os.path.isfile(beside) else {}
    learned = any(np.any(np.isfinite(tr["learned_h"])) for tr in roll.trajs)
    model = setting(metrics, "model") or ("hnn" if learned else "baseline")
    if model not in MODELS:
        raise PlotError(f"{beside}: model '{model}' is not one of {', '.join(MODELS)}")
    return {"path": path, "task": setting(metrics, "task") or "rollout", "model": model,
            "metrics": metrics, "rollout": roll,
            "of_file": os.path.basename(path) != "rollout.csv"}  # a run's own: its metrics


def plot_rollout_files(paths, out):
    """Figure 2 of each rollout CSV (out/<file>_<model>), and for an HNN's of one degree of
    freedom its learned H against the true one (out/h_contour_<file>)."""
    loaded = [load_rollout_file(p) for p in paths]
    os.makedirs(out, exist_ok=True)
    written, stems = [], set()
    for item in loaded:
        name = os.path.splitext(os.path.basename(item["path"]))[0]
        stem = f"{name}_{item['model']}"
        if stem in stems:  # the same file name from another folder
            stem = f"{os.path.basename(os.path.dirname(os.path.abspath(item['path'])))}_{stem}"
        stems.add(stem)
        runs = {item["model"]: item}
        show_longest([item["rollout"]])
        rolls, truth = rollouts_of(runs)
        title = (item["path"] if item["task"] == "rollout"
                 else f"{run_title(item['task'], runs)}: {item['path']}")
        written += fig2.draw_fig2(out, item["task"], runs, rolls, truth, title=title, stem=stem)
        if item["model"] == "hnn":
            written += draw_contour(out, item["task"], runs, title, item["rollout"],
                                    stem=f"h_contour_{stem}")
    return written
