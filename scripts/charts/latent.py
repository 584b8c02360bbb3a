"""Figure C1 of the paper: the pixel HNN's learned H over its latent plane with the encoded test
trajectories, and the baseline's latent field (figC1_pixel_latent)."""

import os

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, pixel_run, read_csv, read_optional, save


def read_grid(folder):
    """latent_grid.csv of a pixel run folder (learned H and field over the latent plane)."""
    return read_optional(os.path.join(folder, "latent_grid.csv"),
                         lambda p: read_csv(p, ["z_q", "z_p", "learned_h", "dz_q", "dz_p"]))


def draw_latent_panel(ax, grid, paths, model, title):
    n = int(round(np.sqrt(len(grid["z_q"]))))
    zq, zp = grid["z_q"].reshape(n, n), grid["z_p"].reshape(n, n)
    h = grid["learned_h"].reshape(n, n)
    if np.all(np.isfinite(h)):
        # Levels at quantiles of H over the grid: H grows fast towards the corners, and evenly
        # spaced levels would leave the encoded trajectories only a few rings.
        levels = np.unique(np.quantile(h, np.linspace(0, 1, 21)))
        contour = ax.contourf(zq, zp, h, levels=levels, cmap="viridis")
        plt.colorbar(contour, ax=ax, label="learned H")
    else:  # the baseline learns no H: its field instead
        ax.streamplot(zq[:, 0], zp[0, :], grid["dz_q"].reshape(n, n).T,
                      grid["dz_p"].reshape(n, n).T, color="0.6", density=1.0, linewidth=0.7)
    if paths is not None:
        for k in np.unique(paths["traj"]):
            rows = paths["traj"] == k
            ax.plot(paths["z_q"][rows], paths["z_p"][rows], color="white" if np.all(
                np.isfinite(h)) else COLORS[model], lw=0.8, alpha=0.9)
    ax.set(title=title, xlabel="$z_q$", ylabel="$z_p$")


def draw_fig_c1(results):
    panels = []
    for model in ("hnn", "baseline"):
        d = pixel_run(results, model)
        grid = read_grid(d)
        paths = read_optional(os.path.join(d, "latent_paths.csv"),
                              lambda p: read_csv(p, ["traj", "k", "z_q", "z_p"]))
        if grid is not None:
            panels.append((model, grid, paths))
    if not panels:
        return []
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), squeeze=False)
    for ax, (model, grid, paths) in zip(axes[0], panels):
        title = ("HNN: learned H and encoded test trajectories" if model == "hnn"
                 else "Baseline: learned latent field and encoded trajectories")
        draw_latent_panel(ax, grid, paths, model, title)
    fig.tight_layout()
    return save(fig, results, "figC1_pixel_latent")
