"""The command of scripts/plot_pixel.py: the pixel pendulum's charts (Figures 4, C1 and 5) and
the reversibility chart of an hnn results folder."""

import argparse
import os

from . import bump, fig4_pixel, latent, reversibility
from .common import PIXEL_TASK, PlotError, error, note


def parser():
    p = argparse.ArgumentParser(
        prog="plot_pixel.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Charts of the pixel pendulum (task 5) and of reversibility, from an hnn"
                    " results folder.",
        epilog="""Reads RESULTS_DIR/pixel-pendulum/{baseline,hnn}/ (pixel_rollout.csv, latent_grid.csv,
latent_paths.csv, bump.csv, metrics.json), RESULTS_DIR/pixel-pendulum/rollout_strip.png (from
`hnn animate` or `hnn reproduce`) and RESULTS_DIR/reversibility.json, and writes into RESULTS_DIR:
  fig4_pixel_pendulum   the strip of frames (truth, baseline, HNN), frame MSE and energy vs time
  figC1_pixel_latent    learned H over the latent plane with encoded test trajectories; fields
  fig5_pixel_bump       the energy bump: latent path over H, learned H and energy vs time
  reversibility         return distance after forward-then-backward integration, every run
Missing inputs are skipped with a note on stderr; unreadable ones are errors (exit code 1).""")
    p.add_argument("results", metavar="RESULTS_DIR")
    return p


def main(argv):
    """scripts/plot_pixel.py's command line (argv without the program's name); the exit code."""
    results = parser().parse_args(argv).results
    if not os.path.isdir(results):
        return error(f"{results}: not a folder")
    try:
        written = []
        if os.path.isdir(os.path.join(results, PIXEL_TASK)):
            written += (fig4_pixel.draw_fig4(results) + latent.draw_fig_c1(results)
                        + bump.draw_fig5(results))
        else:
            note(f"{PIXEL_TASK}: no runs, pixel charts skipped")
        written += reversibility.draw_reversibility(results)
    except PlotError as e:
        return error(e)
    if not written:
        note(f"{results}: nothing to draw")
    return 0
