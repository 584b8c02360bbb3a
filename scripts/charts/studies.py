"""The command of scripts/plot_study.py: the charts and tables of a study that `hnn sweep` ran
from a spec of sweeps/, read from the sweep's results.csv."""

import argparse
import os
import shutil

import matplotlib.pyplot as plt

from . import data_table, dhnn_table, float_double, lean, model_size, rollout_table
from .common import GRID, PlotError, error, present
from .sweep_table import finished, read_results, with_sizes


def draw_model_size(rows, sweep, out):
    """Charts 3 and 4 of docs/speed_accuracy.md and lean.csv; the table beside them as
    model_size.csv."""
    rows = with_sizes(finished(rows), os.path.join(sweep, "results.csv"))
    paper = [r for r in rows if r["hidden"] == lean.PAPER and r["seed"] == "0"]
    double = [r for r in rows if r["dtype"] == "double"]
    if not present(paper) or not double:
        raise PlotError(f"{sweep}/results.csv: no finished runs of the model-size study")
    if os.path.abspath(out) != os.path.abspath(sweep):
        copy = os.path.join(out, "model_size.csv")
        shutil.copy(os.path.join(sweep, "results.csv"), copy + ".tmp")
        os.replace(copy + ".tmp", copy)
        print(copy)
    with plt.rc_context(GRID):
        float_double.plot_float_double(paper, out)
        model_size.plot_model_size(double, out)


# name: (what it draws, the spec, the columns it needs, how)
STUDIES = {
    "model_size": ("charts 3 and 4 of docs/speed_accuracy.md (float_double, model_size) and the"
                   " lean table (lean.csv), with the table as model_size.csv",
                   "sweeps/model_size.yaml", ("task", "model", "dtype", "hidden", "seed"),
                   draw_model_size),
    "data_results": ("docs/data_results.md's tables (results.md) and Figure 2 of each system"
                     " (charts/NAME/fig2_data)", "sweeps/data_results.yaml",
                     ("task", "model", "data"), data_table.draw),
    "dhnn": ("docs/families.md's D-HNN table beside the peers' numbers (results.md)",
             "sweeps/dhnn.yaml", ("task", "model"), dhnn_table.draw),
    "rollout": ("docs/families.md's tables of the rollout loss (results.md)",
                "sweeps/rollout.yaml", ("task", "model", "settings", "loss", "integrator"),
                rollout_table.draw),
}


def parser():
    p = argparse.ArgumentParser(
        prog="plot_study.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="The charts and tables of a study from its sweep folder:"
                    " `hnn sweep sweeps/STUDY.yaml --out SWEEP_DIR` first.",
        epilog="studies:\n" + "\n".join(f"  {name:13} {spec}: {what}" for name, (what, spec, _, _)
                                        in STUDIES.items())
        + "\nEach written file's path goes to stdout; runs that failed or are pending get a note"
          " on stderr.")
    p.add_argument("study", choices=list(STUDIES), metavar="STUDY",
                   help=", ".join(STUDIES))
    p.add_argument("sweep", metavar="SWEEP_DIR", help="the folder of `hnn sweep --out`")
    p.add_argument("--out", metavar="DIR", help="where to write (default: SWEEP_DIR)")
    return p


def main(argv):
    """scripts/plot_study.py's command line (argv without the program's name)."""
    args = parser().parse_args(argv)
    _, _, columns, draw = STUDIES[args.study]
    out = args.out or args.sweep
    try:
        rows = read_results(args.sweep, columns)
        os.makedirs(out, exist_ok=True)
        draw(rows, args.sweep, out)
    except (PlotError, OSError) as e:
        return error(e)
    return 0
