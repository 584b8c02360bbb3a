"""The command of scripts/plot.py: every chart of an `hnn reproduce` results folder (Figures 2
and 3, the training curves, the Table 1 chart), or the charts of `hnn train` run folders
(--runs) and of rollout CSV files (--rollouts), drawn by runs.py."""

import argparse
import os

from . import fig2, fig3, table1, training_curves
from .common import (MODELS, PIXEL_TASK, TASKS, PlotError, error, note, read_json,
                     read_loss_curve)
from .rollout import Rollout, rollouts_of
from .runs import plot_rollout_files, plot_runs


def load_model(task_dir, task, model):
    """{'metrics', 'loss', 'rollout'} for one model; a missing file gives None (with a note)."""
    model_dir = os.path.join(task_dir, model)
    if not os.path.isdir(model_dir):
        note(f"{task}/{model}: missing, skipped")
        return None
    run = {}
    readers = {"metrics": ("metrics.json", read_json),
               "loss": ("loss_curve.csv", read_loss_curve),
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


def parser():
    p = argparse.ArgumentParser(
        prog="plot.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        usage="%(prog)s RESULTS_DIR\n       %(prog)s --runs RUN [RUN ...] --out DIR\n"
              "       %(prog)s --rollouts CSV [CSV ...] --out DIR",
        description="Renders every chart of an hnn results folder to PNG and SVG, or the charts"
                    " of run folders or of rollout CSV files.",
        epilog="""RESULTS_DIR: reads table1.json and <task>/<model>/{metrics.json,loss_curve.csv,
rollout.csv} as written by `hnn reproduce`, and writes into RESULTS_DIR:
  fig2_<task>       2-D tasks: phase space, coordinate MSE, HNN-conserved quantity, energy
  fig3_<task>       n-body tasks: orbits (truth / baseline / HNN), coordinate MSE, energy
  training_curves   train and test loss vs step, one panel per task
  table1_chart      test loss and energy MSE, ours vs the paper's Table 1
Missing tasks, models or files are skipped with a one-line note on stderr; a file that cannot
be parsed is an error naming it (exit code 1). Each written file's path goes to stdout.

--runs draws any run folders (`hnn train ... --out RUN`, e.g. of the `data` task), at most one
per model and all of one task and the same held-out data, into DIR:
  fig2_<task>       Figure 2 of their test rollouts (rollout.csv): q_1 against p_1 (names from
                    metrics.json's "state_names"), the coordinate MSE against the time since
                    each rollout's start, and the energies; without a known Hamiltonian (the truth's
                    rows have empty energy cells) the last panel is the drift of the HNN's learned H
  training_curves   their loss curves (loss_curve.csv), train solid, test dashed
  h_contour_<task>  one degree of freedom and an HNN run: the true energy and the learned H over
                    the phase plane, interpolated between the test rollouts; the learned H is
                    shifted to equal the true energy where the shown rollout starts (H is
                    defined only up to a constant)
  h_slice_<task>    more degrees of freedom and an HNN run: the true energy and the learned H
                    on a 2-D slice (the first coordinate and its momentum, the others held at
                    the shown rollout's start), from `hnn hamiltonian` (found as $HNN,
                    build/apps/hnn or on the PATH; its grid is kept as h_grid_<task>.csv) or
                    from --h-grid CSV; the learned H is shifted by the constant that fits it
                    best to the true energy, printed on the panel
  rollout_<integrator>_<task>  Figure 2 of the runs' `hnn rollout` files
A run that lacks metrics.json or rollout.csv, or runs of different tasks or data, are an error
naming them.

--rollouts draws any rollout CSV hnn writes (a run's rollout.csv, `hnn rollout`'s
rollout_<integrator>.csv, one layout: tasks/report/rollout_csv.h) into DIR/<file>_<model> (Figure 2) and, for an HNN of
one degree of freedom, DIR/h_contour_<file>_hnn; the task, the model and the state's names come
from the metrics.json beside the file when there is one.""")
    p.add_argument("results", nargs="?", metavar="RESULTS_DIR", help="an `hnn reproduce` folder")
    p.add_argument("--runs", nargs="+", metavar="RUN", help="`hnn train` run folders")
    p.add_argument("--rollouts", nargs="+", metavar="CSV", help="rollout CSV files of hnn")
    p.add_argument("--out", metavar="DIR", help="where --runs and --rollouts write")
    p.add_argument("--h-grid", metavar="CSV",
                   help="with --runs: the learned H's slice from this `hnn hamiltonian` CSV")
    return p


def main(argv):
    """scripts/plot.py's command line (argv without the program's name); returns the exit code."""
    p = parser()
    args = p.parse_args(argv)
    if args.runs is not None or args.rollouts is not None:
        if args.results is not None or args.out is None or None not in (args.runs,
                                                                        args.rollouts):
            p.error("--runs or --rollouts takes --out DIR, and no RESULTS_DIR")
        if args.h_grid is not None and args.runs is None:
            p.error("--h-grid goes with --runs")
        try:
            if args.runs is not None:
                plot_runs(args.runs, args.out, args.h_grid)
            else:
                plot_rollout_files(args.rollouts, args.out)
        except (PlotError, OSError) as e:
            return error(e)
        return 0
    if args.results is None or args.out is not None:
        p.error("give RESULTS_DIR, or --runs RUN ... --out DIR, or --rollouts CSV ... --out DIR")
    if not os.path.isdir(args.results):
        return error(f"{args.results}: not a folder")
    try:
        written = plot_all(args.results)
    except PlotError as e:
        return error(e)
    if not written:
        note(f"{args.results}: nothing to draw")
    return 0
