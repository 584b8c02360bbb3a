#!/usr/bin/python3
"""Charts of the pixel pendulum (task 5) and of reversibility, from an hnn results folder.

Usage: /usr/bin/python3 scripts/plot_pixel.py RESULTS_DIR

Reads RESULTS_DIR/pixel-pendulum/{baseline,hnn}/ (pixel_rollout.csv, latent_grid.csv,
latent_paths.csv, bump.csv, metrics.json), RESULTS_DIR/pixel-pendulum/rollout_strip.png (from
`hnn animate` or `hnn reproduce`) and RESULTS_DIR/reversibility.json, and writes into RESULTS_DIR:
  fig4_pixel_pendulum   the strip of frames (truth, baseline, HNN), frame MSE and energy vs time
  figC1_pixel_latent    learned H over the latent plane with encoded test trajectories; fields
  fig5_pixel_bump       the energy bump: latent path over H, learned H and energy vs time
  reversibility         return distance after forward-then-backward integration, every run
Missing inputs are skipped with a note on stderr; unreadable ones are errors (exit code 1).
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot  # noqa: E402  (shared readers, colours and the atomic PNG+SVG writer)
from plot import COLORS, LABELS, PlotError, note, plt, read_csv, read_json, save  # noqa: E402

TASK = "pixel-pendulum"
PHASE_COLORS = {"symplectic": "tab:blue", "riemann": "tab:purple", "symplectic-after": "tab:red"}


def model_dir(results, model):
    return os.path.join(results, TASK, model)


def read_optional(path, reader):
    if not os.path.isfile(path):
        note(f"{os.path.relpath(path)}: missing, skipped")
        return None
    return reader(path)


def by_traj(cols):
    """{traj: {column: values}} ordered by frame."""
    out = {}
    for k in np.unique(cols["traj"]):
        rows = cols["traj"] == k
        order = np.argsort(cols["frame"][rows], kind="stable")
        out[int(k)] = {name: v[rows][order] for name, v in cols.items()}
    return out


def read_rollout(results, model):
    path = os.path.join(model_dir(results, model), "pixel_rollout.csv")
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
    strip = os.path.join(results, TASK, "rollout_strip.png")
    has_strip = os.path.isfile(strip)
    if not has_strip:
        note(f"{TASK}/rollout_strip.png: missing (run `hnn animate`), strip skipped")
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
        d = model_dir(results, model)
        grid = read_optional(os.path.join(d, "latent_grid.csv"),
                             lambda p: read_csv(p, ["z_q", "z_p", "learned_h", "dz_q", "dz_p"]))
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


def draw_fig5(results):
    d = model_dir(results, "hnn")
    path = os.path.join(d, "bump.csv")
    if not os.path.isfile(path):
        note(f"{TASK}/hnn/bump.csv: missing (run `hnn bump`), Figure 5 skipped")
        return []
    # phase is text: read it apart from the numeric columns.
    with open(path, encoding="utf-8") as f:
        lines = [line.rstrip("\n").split(",") for line in f if line.strip()]
    header = lines[0]
    if header[0] != "phase":
        raise PlotError(f"{path}: first column should be 'phase', got {header[0]!r}")
    phases = np.array([row[0] for row in lines[1:]])
    values = {h: np.array([plot.to_float(row[i], path, n + 2, h) for n, row in enumerate(lines[1:])])
              for i, h in enumerate(header) if i > 0}
    grid = read_optional(os.path.join(d, "latent_grid.csv"),
                         lambda p: read_csv(p, ["z_q", "z_p", "learned_h", "dz_q", "dz_p"]))
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


def draw_reversibility(results):
    path = os.path.join(results, "reversibility.json")
    if not os.path.isfile(path):
        note("reversibility.json: missing (run `hnn reversibility --report`), chart skipped")
        return []
    rows = read_json(path)
    if not isinstance(rows, list):
        raise PlotError(f"{path}: expected a list of runs")
    integrators = ["midpoint", "rk4", "dopri5"]
    labels = [f"{r.get('task')}\n{r.get('model')}" for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.0), gridspec_kw={"width_ratios": [3, 1.3]})
    width = 0.8 / len(integrators)
    for j, name in enumerate(integrators):
        values = []
        for r in rows:
            found = [i for i in r.get("integrators", []) if i.get("integrator") == name]
            v = found[0].get("return_distance_mean") if found else None
            values.append(v if isinstance(v, (int, float)) and v > 0 else np.nan)
        axes[0].bar(np.arange(len(rows)) + (j - 1) * width, values, width, label=name)
    axes[0].set_yscale("log")
    axes[0].set_xticks(np.arange(len(rows)))
    axes[0].set_xticklabels(labels, fontsize=7)
    axes[0].set(title="Forward then backward: mean return distance", ylabel="|x_back - x0|")
    axes[0].legend(loc="best")
    dets = [r.get("volume", {}).get("abs_log_det_mean") for r in rows]
    dets = [d if isinstance(d, (int, float)) and d > 0 else np.nan for d in dets]
    colors = [COLORS.get(r.get("model"), "0.5") for r in rows]
    axes[1].barh(np.arange(len(rows)), dets, color=colors)
    axes[1].set_xscale("log")
    axes[1].set_yticks(np.arange(len(rows)))
    axes[1].set_yticklabels([lbl.replace("\n", " ") for lbl in labels], fontsize=7)
    axes[1].invert_yaxis()
    axes[1].set(title="|log det| of the flow map (0 = volume kept)")
    fig.tight_layout()
    return save(fig, results, "reversibility")


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    results = argv[1]
    if not os.path.isdir(results):
        print(f"plot_pixel.py: error: {results}: not a folder", file=sys.stderr)
        return 1
    try:
        written = []
        if os.path.isdir(os.path.join(results, TASK)):
            written += draw_fig4(results) + draw_fig_c1(results) + draw_fig5(results)
        else:
            note(f"{TASK}: no runs, pixel charts skipped")
        written += draw_reversibility(results)
    except PlotError as e:
        print(f"plot_pixel.py: error: {e}", file=sys.stderr)
        return 1
    if not written:
        note(f"{results}: nothing to draw")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
