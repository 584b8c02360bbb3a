"""The learned H beside the true one over the phase plane of a one-degree-of-freedom system
(h_contour_<task>), from a run's rollout CSV alone: the true energy along the true paths and
the HNN's learned H along its own, interpolated between the paths (matplotlib's triangulation).
The learned H is drawn shifted by the constant that makes it equal the true energy where the
shown rollout starts, as H is defined only up to a constant."""

import matplotlib.pyplot as plt
import matplotlib.tri as mtri
import numpy as np

from .common import PlotError, note, save
from .rollout import clamp_limits, set_limits


def points(roll, states, values):
    """(x, y, value) of every sample of every trajectory where all three are finite, without
    repeats (a triangulation refuses duplicate points)."""
    xy = np.concatenate([tr[states] for tr in roll.trajs])
    v = np.concatenate([tr[values] for tr in roll.trajs])
    ok = np.all(np.isfinite(xy), axis=1) & np.isfinite(v)
    _, first = np.unique(np.round(xy[ok], 12), axis=0, return_index=True)
    keep = np.sort(first)
    return xy[ok][keep, 0], xy[ok][keep, 1], v[ok][keep]


def reference_shift(roll):
    """(shift, state): the constant that makes the learned H equal the true energy at the
    shown rollout's first state (the true state the rollout starts from), and that state; (0,
    None) without a true energy there."""
    tr = roll.shown
    e0, h0 = tr["true_energy"][0], tr["learned_h"][0]
    if np.isfinite(e0) and np.isfinite(h0):
        return float(e0 - h0), tr["true"][0]
    return 0.0, None


def contour_panel(ax, roll, which, levels, shift, title):
    """Filled contours of the true energy (which="true") or the learned H + shift ("pred") with
    the paths they come from in white; returns the contour set, or None (with a note) when the
    samples span no area."""
    x, y, v = points(roll, which, "true_energy" if which == "true" else "learned_h")
    try:
        triangles = mtri.Triangulation(x, y)
        filled = ax.tricontourf(triangles, v + shift, levels=levels, cmap="viridis",
                                extend="both")
    except (ValueError, RuntimeError) as e:
        note(f"{roll.path}: the {which} states span no area ({e}); contour skipped")
        return None
    for tr in roll.trajs:
        ax.plot(tr[which][:, 0], tr[which][:, 1], color="white", lw=0.5, alpha=0.7)
    ax.set_title(title)
    return filled


def draw_h_contour(out, task, roll, names, title, stem=None):
    """Two panels, the true energy and the learned H + c, on the same colour levels; one (the
    learned H as learned) without a true energy. Needs a 2-D state and an HNN rollout with its
    learned H; otherwise a note and nothing drawn."""
    if roll.d != 2:
        note(f"{roll.path}: a state of {roll.d} dimensions; the H contour needs one degree of"
             " freedom (q, p), skipped")
        return []
    if not any(np.any(np.isfinite(tr["learned_h"])) for tr in roll.trajs):
        raise PlotError(f"{roll.path}: no learned_h values (not an HNN rollout?)")
    shift, start = reference_shift(roll)
    truth = any(np.any(np.isfinite(tr["true_energy"])) for tr in roll.trajs)
    source = points(roll, "true", "true_energy")[2] if truth else (
        points(roll, "pred", "learned_h")[2] + shift)
    levels = np.linspace(np.min(source), np.max(source), 16)
    if levels[0] == levels[-1]:
        levels = levels[0] + np.linspace(-1, 1, 16) * max(1e-12, abs(levels[0]) * 1e-6)
    fig, axes = plt.subplots(1, 2 if truth else 1, figsize=(11, 4.6) if truth else (6, 4.6),
                             layout="constrained", squeeze=False)
    axes = axes[0]
    drawn = []
    if truth:
        drawn.append(contour_panel(axes[0], roll, "true", levels, 0.0,
                                   "True energy E (along the true paths)"))
    where = (f"{names[0]} = {start[0]:.3g}, {names[1]} = {start[1]:.3g}" if start is not None
             else "")
    learned_title = (f"Learned H + {shift:.4g}: equal to E at the start of test trajectory"
                     f" {roll.show}\n({where}); H is defined only up to a constant"
                     if truth else "Learned H, as learned (defined only up to a constant;\n"
                     "no known Hamiltonian to compare with)")
    drawn.append(contour_panel(axes[-1], roll, "pred", levels, shift, learned_title))
    if all(c is None for c in drawn):
        plt.close(fig)
        return []
    every = np.concatenate([tr["true"] for tr in roll.trajs])
    for ax in axes:
        set_limits(ax.set_xlim, clamp_limits(every[:, 0], every[:, 0], margin=0.3))
        set_limits(ax.set_ylim, clamp_limits(every[:, 1], every[:, 1], margin=0.3))
        ax.set(xlabel=names[0], ylabel=names[1])
    colours = next(c for c in drawn if c is not None)
    fig.colorbar(colours, ax=list(axes), label="H (white: the paths it is interpolated between)")
    fig.suptitle(f"{title}: true and learned H over the phase plane, from the"
                 f" {len(roll.trajs)} test rollouts of {roll.path}")
    return save(fig, out, stem or f"h_contour_{task}")
