"""Figure 4 of the paper: the pixel pendulum's strip of decoded frames (truth, baseline, HNN),
the frame MSE and the energy against time (fig4_pixel_pendulum)."""

import os

import matplotlib.pyplot as plt
import numpy as np

from .common import (COLORS, LABELS, PIXEL_TASK, note, pixel_run, read_csv, read_optional,
                     save)


def by_traj(cols):
    """{traj: {column: values}} ordered by frame."""
    out = {}
    for k in np.unique(cols["traj"]):
        rows = cols["traj"] == k
        order = np.argsort(cols["frame"][rows], kind="stable")
        out[int(k)] = {name: v[rows][order] for name, v in cols.items()}
    return out


def read_rollout(results, model):
    path = os.path.join(pixel_run(results, model), "pixel_rollout.csv")
    return read_optional(path, lambda p: read_csv(p, [
        "traj", "frame", "frame_mse", "true_energy", "pred_energy", "pred_theta", "true_theta"]))


def mean_over_traj(cols, key):
    trajs = by_traj(cols)
    n = min(len(t["frame"]) for t in trajs.values())
    return trajs[min(trajs)]["frame"][:n], np.nanmean(
        np.stack([t[key][:n] for t in trajs.values()]), axis=0)


def draw_fig4(results):
    rolls = {m: read_rollout(results, m) for m in ("baseline", "hnn")}
    if all(r is None for r in rolls.values()):
        return []
    strip = os.path.join(results, PIXEL_TASK, "rollout_strip.png")
    has_strip = os.path.isfile(strip)
    if not has_strip:
        note(f"{PIXEL_TASK}/rollout_strip.png: missing (run `hnn animate`), strip skipped")
    image = plt.imread(strip) if has_strip else None
    # The strip's row is as tall as the image needs at the figure's width (plus its labels).
    strip_height = 10 * image.shape[0] / image.shape[1] + 0.9 if has_strip else 0
    fig = plt.figure(figsize=(10, 3.6 + strip_height))
    grid = fig.add_gridspec(2 if has_strip else 1, 3,
                            height_ratios=[strip_height, 3.6] if has_strip else [1])
    if has_strip:
        ax = fig.add_subplot(grid[0, :])
        ax.imshow(image, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        rows = 3
        height = image.shape[0] / rows
        ax.set_yticks([height * (i + 0.5) for i in range(rows)])
        ax.set_yticklabels([LABELS["truth"], LABELS["baseline"], LABELS["hnn"]])
        tiles = (image.shape[1] - 2) / (28 * 2 + 2)
        ax.set_xticks([(i + 0.5) * image.shape[1] / tiles for i in range(int(round(tiles)))])
        ax.set_xticklabels([str(10 * i) for i in range(int(round(tiles)))])
        ax.set_xlabel("frame")
        ax.set_title("Pixel pendulum: latent rollouts decoded to frames (every 10th frame)")
    row = 1 if has_strip else 0
    ax_mse, ax_e, ax_one = (fig.add_subplot(grid[row, i]) for i in range(3))
    for model, cols in rolls.items():
        if cols is None:
            continue
        t, mse = mean_over_traj(cols, "frame_mse")
        ax_mse.plot(t, mse, color=COLORS[model], label=LABELS[model])
        t, e = mean_over_traj(cols, "pred_energy")
        ax_e.plot(t, e, color=COLORS[model], label=LABELS[model])
        first = by_traj(cols)[0]
        ax_one.plot(first["frame"], first["pred_energy"], color=COLORS[model], label=LABELS[model])
    reference = next(c for c in rolls.values() if c is not None)
    t, e = mean_over_traj(reference, "true_energy")
    ax_e.plot(t, e, color=COLORS["truth"], ls="--", label=LABELS["truth"])
    first = by_traj(reference)[0]
    ax_one.plot(first["frame"], first["true_energy"], color=COLORS["truth"], ls="--",
                label=LABELS["truth"])
    ax_mse.set(title="Frame MSE (mean over rollouts)", xlabel="frame", yscale="log")
    ax_e.set(title="Energy from decoded frames (mean)", xlabel="frame", ylabel="energy")
    ax_one.set(title="Energy, first test trial", xlabel="frame")
    ax_e.legend(loc="best")
    fig.tight_layout()
    return save(fig, results, "fig4_pixel_pendulum")
