"""The command of scripts/plot_speed_accuracy.py: the speed-against-accuracy charts of
docs/speed_accuracy.md from the CSV files of bench/accuracy/ (scripts/charts.sh runs it)."""

import argparse
import os
import sys

import matplotlib.pyplot as plt

from . import energy_drift, fd_error, fd_time, work_precision
from .common import GRID

CHARTS = [("fd_error.csv", fd_error.plot_fd_error), ("fd_time_dim.csv", fd_time.plot_fd_time),
          ("work_precision.csv", work_precision.plot_work_precision),
          ("energy_drift.csv", energy_drift.plot_energy_drift)]


def parser():
    p = argparse.ArgumentParser(
        prog="plot_speed_accuracy.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Draws the speed-against-accuracy charts from the CSV files of"
                    " bench/accuracy/.",
        epilog="""Reads from DIR (as written by fd_vs_autodiff and work_precision, see scripts/charts.sh):
  fd_error.csv, fd_time_dim.csv, fd_time_params.csv, work_precision.csv, energy_drift.csv
and writes into DIR, each as PNG and SVG:
  fd_error         error of finite differences against the step h, autodiff's as a flat line
  fd_time          time of a gradient against input dimension and against parameter count
  work_precision   integrators: error at t = 10 against wall time and field evaluations
  energy_drift     relative energy error over long horizons, true systems and a trained HNN
A missing CSV skips its chart with a note on stderr. Each written file's path goes to stdout.""")
    p.add_argument("directory", metavar="DIR")
    return p


def main(argv):
    """scripts/plot_speed_accuracy.py's command line (argv without the program's name)."""
    directory = parser().parse_args(argv).directory
    for name, draw in CHARTS:
        if not os.path.exists(os.path.join(directory, name)):
            print(f"plot_speed_accuracy: {name} missing, chart skipped", file=sys.stderr)
            continue
        with plt.rc_context(GRID):
            draw(directory)
    return 0
