"""The command of scripts/plot.py: every chart of an `hnn reproduce` results folder (Figures 2
and 3, the training curves, the Table 1 chart), or Figure 2 of `hnn train` run folders
(--runs)."""

import argparse
import os

import numpy as np

from . import fig2, fig3, table1, training_curves
from .common import MODELS, PIXEL_TASK, TASKS, TITLES, PlotError, error, note, read_csv, read_json
from .rollout import Rollout, rollouts_of, setting


def load_model(task_dir, task, model):
    """{'metrics', 'loss', 'rollout'} for one model; a missing file gives None (with a note)."""
    model_dir = os.path.join(task_dir, model)
    if not os.path.isdir(model_dir):
        note(f"{task}/{model}: missing, skipped")
        return None
    run = {}
    readers = {"metrics": ("metrics.json", read_json),
               "loss": ("loss_curve.csv",
                        lambda p: read_csv(p, ["step", "train_loss", "test_loss"])),
               "rollout": ("rollout.csv", Rollout)}
    for key, (name, reader) in readers.items():
        path = os.path.join(model_dir, name)
        if os.path.isfile(path):
            run[key] = reader(path)
        else:
            run[key] = None
            note(f"{task}/{model}/{name}: missing, skipped")
    if run["metrics"] is not None and not isinstance(run["metrics"], dict):
        raise PlotError(f"{os.path.join(model_dir, 'metrics.json')}: expected a JSON object")
    return run


def find_tasks(results):
    """Known tasks in paper order, then any other folder holding a model folder."""
    extra = sorted(n for n in os.listdir(results) if n not in TASKS and any(
        os.path.isdir(os.path.join(results, n, m)) for m in MODELS))
    return TASKS + extra


# ---------------------------------------------------------------------------------------------
# A results folder: every chart


def draw_rollout_charts(results, task, runs):
    """fig2 for a 2-D state, fig3 for n bodies in the plane (d = 4n)."""
    if not any(runs.get(m) and runs[m]["rollout"] for m in MODELS):
        note(f"{task}: no rollout.csv, rollout charts skipped")
        return []
    if task == PIXEL_TASK:
        return []  # charts/fig4_pixel.py draws them
    rolls, truth = rollouts_of(runs)
    d = truth["true"].shape[1]
    if d == 2:
        return fig2.draw_fig2(results, task, runs, rolls, truth)
    if d % 4 == 0:
        return fig3.draw_fig3(results, task, runs, rolls, truth)
    note(f"{task}: state dimension {d} has no chart, skipped")
    return []


def plot_all(results):
    """Reads every input first (so a malformed file stops the run before anything is written),
    then draws every chart the folder supports; returns the list of files written."""
    all_runs = {}
    for task in find_tasks(results):
        task_dir = os.path.join(results, task)
        if not os.path.isdir(task_dir):
            note(f"{task}: no results, skipped")
            continue
        all_runs[task] = {m: load_model(task_dir, task, m) for m in MODELS}
    rows = table1.read_table1(results)
    written = []
    for task, runs in all_runs.items():
        written += draw_rollout_charts(results, task, runs)
    written += training_curves.draw_training_curves(results, all_runs)
    if rows is not None:
        written += table1.draw_table1_chart(results, rows)
    return written


# ---------------------------------------------------------------------------------------------
# --runs: Figure 2 of run folders


def load_run(folder):
    """{'folder', 'task', 'model', 'metrics', 'loss', 'rollout'} of one `hnn train` run folder;
    a missing or unusable file is an error naming it."""
    if not os.path.isdir(folder):
        raise PlotError(f"{folder}: not a folder")
    run = {"folder": folder, "loss": None}
    for key, name, reader in (("metrics", "metrics.json", read_json),
                              ("rollout", "rollout.csv", Rollout)):
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            raise PlotError(f"{path}: missing (is {folder} a finished run folder?)")
        run[key] = reader(path)
        if key == "metrics" and not isinstance(run["metrics"], dict):
            raise PlotError(f"{path}: expected a JSON object")
    for key in ("task", "model"):
        value = setting(run["metrics"], key)
        if not isinstance(value, str) or not value:
            raise PlotError(f"{os.path.join(folder, 'metrics.json')}: no '{key}' setting")
        run[key] = value
    if run["model"] not in MODELS:
        raise PlotError(f"{os.path.join(folder, 'metrics.json')}: model '{run['model']}' is not"
                        f" one of {', '.join(MODELS)}")
    return run


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
        a, b = first["rollout"].trajs, run["rollout"].trajs
        same = len(a) == len(b) and all(
            len(x["t"]) == len(y["t"]) and np.allclose(x["t"], y["t"], rtol=1e-9, atol=0.0)
            and np.allclose(x["true"], y["true"], rtol=1e-6, atol=1e-9 * max(
                1.0, float(np.nanmax(np.abs(x["true"]), initial=0.0))), equal_nan=True)
            for x, y in zip(a, b))
        if not same:
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


def plot_runs(folders, out):
    """Figure 2 of the given run folders into out/fig2_<task>; returns the files written."""
    loaded = [load_run(folder) for folder in folders]
    runs = check_runs(loaded)
    task = loaded[0]["task"]
    if task == PIXEL_TASK:
        raise PlotError(f"{task}: rollouts of frames; scripts/plot_pixel.py draws them")
    os.makedirs(out, exist_ok=True)
    trajs = loaded[0]["rollout"].trajs  # the longest shows most: the first of one length
    show = max(range(len(trajs)), key=lambda k: (trajs[k]["t"][-1] - trajs[k]["t"][0], -k))
    for run in loaded:
        run["rollout"].show = show
    rolls, truth = rollouts_of(runs)
    return fig2.draw_fig2(out, task, runs, rolls, truth, title=run_title(task, runs))


# ---------------------------------------------------------------------------------------------


def parser():
    p = argparse.ArgumentParser(
        prog="plot.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        usage="%(prog)s RESULTS_DIR\n       %(prog)s --runs RUN [RUN ...] --out DIR",
        description="Renders every chart of an hnn results folder to PNG and SVG, or Figure 2 of"
                    " run folders.",
        epilog="""RESULTS_DIR: reads table1.json and <task>/<model>/{metrics.json,loss_curve.csv,
rollout.csv} as written by `hnn reproduce`, and writes into RESULTS_DIR:
  fig2_<task>       2-D tasks: phase space, coordinate MSE, HNN-conserved quantity, energy
  fig3_<task>       n-body tasks: orbits (truth / baseline / HNN), coordinate MSE, energy
  training_curves   train and test loss vs step, one panel per task
  table1_chart      test loss and energy MSE, ours vs the paper's Table 1
Missing tasks, models or files are skipped with a one-line note on stderr; a file that cannot
be parsed is an error naming it (exit code 1). Each written file's path goes to stdout.

--runs draws Figure 2 of any run folders (`hnn train ... --out RUN`, e.g. of the `data` task),
at most one per model and all of one task and the same held-out data, into DIR/fig2_<task>:
q_1 against p_1 (names from metrics.json's "state_names"), the coordinate MSE against the time
since each rollout's start, and the energies; without a known Hamiltonian (the truth's rows have
empty energy cells) the last panel is the drift of the HNN's learned H along its own rollout. A run that lacks
metrics.json or rollout.csv, or runs of different tasks or data, are an error naming them.""")
    p.add_argument("results", nargs="?", metavar="RESULTS_DIR", help="an `hnn reproduce` folder")
    p.add_argument("--runs", nargs="+", metavar="RUN", help="`hnn train` run folders")
    p.add_argument("--out", metavar="DIR", help="where --runs writes fig2_<task>")
    return p


def main(argv):
    """scripts/plot.py's command line (argv without the program's name); returns the exit code."""
    p = parser()
    args = p.parse_args(argv)
    if args.runs is not None:
        if args.results is not None or args.out is None:
            p.error("--runs takes --out DIR and no RESULTS_DIR")
        try:
            plot_runs(args.runs, args.out)
        except (PlotError, OSError) as e:
            return error(e)
        return 0
    if args.results is None or args.out is not None:
        p.error("give RESULTS_DIR, or --runs RUN ... --out DIR")
    if not os.path.isdir(args.results):
        return error(f"{args.results}: not a folder")
    try:
        written = plot_all(args.results)
    except PlotError as e:
        return error(e)
    if not written:
        note(f"{args.results}: nothing to draw")
    return 0
