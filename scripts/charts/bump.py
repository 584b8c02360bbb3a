"""Figure 5 of the paper: the energy bump of the pixel HNN, its latent path over H, learned H and
energy against time (fig5_pixel_bump), from the bump.csv of `hnn bump`."""

import os

import matplotlib.pyplot as plt
import numpy as np

from .common import PIXEL_TASK, PlotError, note, pixel_run, save, to_float
from .latent import read_grid

PHASE_COLORS = {"symplectic": "tab:blue", "riemann": "tab:purple", "symplectic-after": "tab:red"}


def draw_fig5(results):
    d = pixel_run(results, "hnn")
    path = os.path.join(d, "bump.csv")
    if not os.path.isfile(path):
        note(f"{PIXEL_TASK}/hnn/bump.csv: missing (run `hnn bump`), Figure 5 skipped")
        return []
    # phase is text: read it apart from the numeric columns.
    with open(path, encoding="utf-8") as f:
        lines = [line.rstrip("\n").split(",") for line in f if line.strip()]
    header = lines[0]
    if header[0] != "phase":
        raise PlotError(f"{path}: first column should be 'phase', got {header[0]!r}")
    phases = np.array([row[0] for row in lines[1:]])
    values = {h: np.array([to_float(row[i], path, n + 2, h) for n, row in enumerate(lines[1:])])
              for i, h in enumerate(header) if i > 0}
    grid = read_grid(d)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    if grid is not None:
        n = int(round(np.sqrt(len(grid["z_q"]))))
        axes[0].contour(grid["z_q"].reshape(n, n), grid["z_p"].reshape(n, n),
                        grid["learned_h"].reshape(n, n), levels=15, colors="0.75", linewidths=0.6)
    for phase, color in PHASE_COLORS.items():
        rows = phases == phase
        label = {"symplectic": "$S_H$ (before)", "riemann": "$R_H$ (bump)",
                 "symplectic-after": "$S_H$ (after)"}[phase]
        axes[0].plot(values["z_q"][rows], values["z_p"][rows], color=color, label=label)
        axes[1].plot(values["t"][rows], values["learned_h"][rows], color=color, label=label)
        axes[2].plot(values["t"][rows], values["energy"][rows], color=color, label=label)
    axes[0].set(title="Latent path: $S_H$, then $R_H$, then $S_H$", xlabel="$z_q$",
                ylabel="$z_p$")
    axes[0].legend(loc="best")
    axes[1].set(title="Learned H", xlabel="t (frames)")
    axes[2].set(title="Energy recovered from decoded frames", xlabel="t (frames)")
    fig.tight_layout()
    return save(fig, results, "fig5_pixel_bump")
