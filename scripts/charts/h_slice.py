"""The learned H beside the true energy on a 2-D slice of a state of more than one degree of
freedom (h_slice_<task>), from the grid CSV of `hnn hamiltonian`
(apps/hnn/commands/hamiltonian.cpp: the two axes' columns first, then the held ones,
learned_h, energy). plot.py --runs makes the
grid by running `hnn hamiltonian` on the HNN run, through the shown test rollout's first state,
or reads one given with --h-grid. The learned H is drawn shifted by the constant that fits it
best to the true energy on the grid (least squares: the mean difference), as H is defined only
up to a constant."""

import os
import shutil
import subprocess

import matplotlib.pyplot as plt
import numpy as np

from .common import PlotError, note, read_csv, save

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def find_hnn():
    """The hnn program, as the scripts find it: $HNN, else the source tree's build/apps/hnn,
    else hnn on the PATH; None when there is none."""
    for candidate in (os.environ.get("HNN"), os.path.join(SOURCE, "build", "apps", "hnn")):
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return candidate
    return shutil.which("hnn")


def slice_through(roll):
    """(grid, at) options of `hnn hamiltonian` for a rollout's slice: its first coordinate and
    that coordinate's momentum over the range of every true path (with a margin of a fifth),
    the other columns held at the shown rollout's first true state."""
    names, n = roll.names, roll.d // 2
    every = np.concatenate([tr["true"] for tr in roll.trajs])
    start = roll.shown["true"][0]
    ranges = []
    for c in (0, n):
        lo, hi = np.nanmin(every[:, c]), np.nanmax(every[:, c])
        pad = 0.2 * (hi - lo) if hi > lo else max(1.0, abs(lo)) * 0.5
        ranges.append(f"{names[c]}={lo - pad:.6g}:{hi + pad:.6g}")
    held = [f"{names[c]}={start[c]:.9g}" for c in range(roll.d) if c not in (0, n)]
    return ",".join(ranges), ",".join(held)


def make_grid(run_folder, roll, out, stem, points=60):
    """Runs `hnn hamiltonian` on run_folder over slice_through(roll) into out/<stem>.csv;
    returns its path, or None (with a note) when there is no hnn program or it fails."""
    hnn = find_hnn()
    if hnn is None:
        note(f"{run_folder}: no hnn program ($HNN, build/apps/hnn or the PATH): the learned-H"
             " slice is skipped (or give --h-grid CSV of `hnn hamiltonian`)")
        return None
    grid, at = slice_through(roll)
    path = os.path.join(out, f"{stem}.csv")
    run = subprocess.run([hnn, "hamiltonian", run_folder, "--grid", grid, "--at", at,
                          "--points", str(points), "--out", path],
                         capture_output=True, text=True, timeout=600)
    if run.returncode != 0:
        note(f"{run_folder}: hnn hamiltonian failed, learned-H slice skipped:"
             f" {run.stderr.strip()}")
        return None
    print(path)
    return path


def read_grid(path):
    """{'names': the two axes', 'x', 'y': their values, 'learned', 'energy': arrays indexed
    [y, x], 'held': [(name, value)]} of a grid CSV of `hnn hamiltonian`."""
    cols = read_csv(path, ["learned_h", "energy"])
    names = [c for c in cols if c not in ("learned_h", "energy")]
    if len(names) < 2:
        raise PlotError(f"{path}: a grid of `hnn hamiltonian` has two axis columns first;"
                        f" got {','.join(cols)}")
    x, y = (np.unique(cols[n]) for n in names[:2])
    if len(x) * len(y) != len(cols["learned_h"]) or len(x) < 2 or len(y) < 2:
        raise PlotError(f"{path}: {len(cols['learned_h'])} rows are not a grid of"
                        f" {len(x)} x {len(y)} points of {names[0]} and {names[1]}")
    order = np.lexsort((cols[names[0]], cols[names[1]]))  # the first axis fastest
    grid = {k: cols[k][order].reshape(len(y), len(x)) for k in ("learned_h", "energy")}
    return {"path": path, "names": names[:2], "x": x, "y": y, "learned": grid["learned_h"],
            "energy": grid["energy"], "held": [(n, float(cols[n][0])) for n in names[2:]]}


def best_shift(g):
    """The constant c minimising the squared difference of learned H + c and the true energy
    over the grid (their mean difference); None without a true energy."""
    ok = np.isfinite(g["energy"]) & np.isfinite(g["learned"])
    return float(np.mean(g["energy"][ok] - g["learned"][ok])) if np.any(ok) else None


def held_text(g):
    """"y = 0, py = 0.5": the held columns, wrapped to lines of six (a three-body state has
    ten)."""
    items = [f"{n} = {v:.3g}" for n, v in g["held"]]
    return ",\n".join(", ".join(items[i:i + 6]) for i in range(0, len(items), 6)) or "nothing"


def draw_h_slice(out, task, g, title, stem=None, labels=None):
    """Two panels on one colour scale, the true energy and the learned H + c, over the grid's
    slice; one (the learned H as learned) without a true energy. Prints the shift. labels:
    the axes' meanings ("q1", "p1") when the grid's columns are only numbered (x_0, x_4)."""
    shift = best_shift(g)
    truth = shift is not None
    source = g["energy"] if truth else g["learned"]
    finite = source[np.isfinite(source)]
    if finite.size == 0:
        raise PlotError(f"{g['path']}: no finite values to draw")
    levels = np.linspace(finite.min(), finite.max(), 16)
    if levels[0] == levels[-1]:
        levels = levels[0] + np.linspace(-1, 1, 16) * max(1e-12, abs(levels[0]) * 1e-6)
    fig, axes = plt.subplots(1, 2 if truth else 1, figsize=(11, 4.8) if truth else (6, 4.8),
                             layout="constrained", squeeze=False)
    axes = axes[0]
    panels = [(g["learned"] + (shift or 0.0),
               f"Learned H + {shift:.4g} (the best constant on this grid)\nH is defined only"
               " up to a constant" if truth else "Learned H, as learned (defined only up to a"
               " constant;\nno known Hamiltonian to compare with)")]
    if truth:
        panels.insert(0, (g["energy"], "True energy E"))
        note(f"{g['path']}: the learned H is drawn + {shift:.6g}, the constant that fits it best"
             " to the true energy on the grid")
    for ax, (values, text) in zip(axes, panels):
        filled = ax.contourf(g["x"], g["y"], values, levels=levels, cmap="viridis",
                             extend="both")
        ax.contour(g["x"], g["y"], values, levels=levels[::3], colors="white", linewidths=0.5,
                   negative_linestyles="solid")
        axis = [n if not labels or labels[k] == n else f"{labels[k]} ({n})"
                for k, n in enumerate(g["names"])]
        ax.set(xlabel=axis[0], ylabel=axis[1], title=text)
    fig.colorbar(filled, ax=list(axes), label="H")
    fig.suptitle(f"{title}: true and learned H on the slice {held_text(g)}"
                 if truth else f"{title}: learned H on the slice {held_text(g)}")
    return save(fig, out, stem or f"h_slice_{task}")
