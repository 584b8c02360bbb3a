"""Figure 2 of the paper: (a) phase space, (b) coordinate MSE, (c) the HNN-conserved quantity,
(d) total energy, for a state of one or more degrees of freedom (fig2_<task>)."""

import matplotlib.pyplot as plt
import numpy as np

from .common import COLORS, LABELS, MODELS, TITLES, is_number, note, save
from .rollout import (clamp_limits, energy_scale, energy_summary, plot_energy_panel,
                      plot_mse_panel, set_limits, setting, time_axis)

def plot_phase_panel(ax, rolls, truth, coords=(0, 1), names=("position q", "momentum p")):
    """The shown trajectory in the plane of the state's columns `coords` (q_1 and p_1), with the
    axis labels `names`."""
    i, j = coords
    ax.plot(truth["true"][:, i], truth["true"][:, j], color=COLORS["truth"], lw=2.2,
            label=LABELS["truth"])
    for model, roll in rolls.items():
        pred = roll.shown["pred"]
        ax.plot(pred[:, i], pred[:, j], color=COLORS[model], lw=1.1, label=LABELS[model])
    ax.plot(truth["true"][0, i], truth["true"][0, j], "o", color=COLORS["truth"], ms=4,
            label="start")
    every = np.concatenate([truth["true"]] + [r.shown["pred"] for r in rolls.values()])
    set_limits(ax.set_xlim, clamp_limits(truth["true"][:, i], every[:, i], margin=1.0))
    set_limits(ax.set_ylim, clamp_limits(truth["true"][:, j], every[:, j], margin=1.0))
    ax.set(title="(a) Predictions (phase space)", xlabel=names[0], ylabel=names[1])
    ax.legend(framealpha=0.9)


def learned_h_spread(metrics):
    """The spread of the learned H over the training states, which a data run's metrics.json
    gives through learned_h_drift (mean over the held-out stretches of max |H(t) - H(t0)|) and
    learned_h_drift_relative (the mean of the same over that spread); None without them."""
    drift, relative = metrics.get("learned_h_drift"), metrics.get("learned_h_drift_relative")
    if is_number(drift) and is_number(relative) and drift > 0 and relative > 0:
        return drift / relative
    return None


def plot_learned_h_panel(ax, rolls, truth, drift=False, spread=None):
    """The HNN's own H along its rollout, with its largest drift from the start written in.
    drift: plot H(t) - H(t0) instead (there is no true energy to compare with), at least 20% of
    `spread` (the learned H's spread on the training states) high if given, so that a well
    conserved H draws flat rather than as magnified round-off."""
    h = rolls["hnn"].shown["learned_h"] if "hnn" in rolls else np.array([np.nan])
    if np.any(np.isfinite(h)):
        t, xlabel = time_axis(rolls["hnn"].shown["t"])
        change = np.nanmax(np.abs(h - h[0]))
        text = f"max |H(t) - H({'t_0' if xlabel != 'time t' else '0'})| = {change:.2e}"
        if drift:
            ax.plot(t, h - h[0], color=COLORS["hnn"], label=LABELS["hnn"])
            set_limits(ax.set_ylim, clamp_limits(h - h[0], h - h[0], min_span=0.2 * (spread or 0)))
            if spread:
                text += f"\n= {100 * change / spread:.2g}% of H's spread on the training states"
        else:
            shift = learned_h_shift(h, truth)
            ax.plot(t, h + shift, color=COLORS["hnn"], label=LABELS["hnn"])
            set_limits(ax.set_ylim, clamp_limits(h + shift, h + shift,
                                                 min_span=energy_scale(truth)))
            if shift:
                text = (f"{text}\nH is defined only up to a constant: drawn + {shift:.4g},"
                        " to equal\nthe true energy at the rollout's start")
        ax.text(0.03, 0.04, text, transform=ax.transAxes)
        ax.legend(loc="upper right")
    else:
        xlabel, why = "time t", "no HNN rollout"
        if drift:
            why = ("the HNN rollout has no learned H\n(did it fail? see metrics.json)"
                   if "hnn" in rolls else "no HNN run: a baseline has no learned H")
        ax.text(0.5, 0.5, why, ha="center", transform=ax.transAxes)
        if drift:
            ax.set(xticks=[], yticks=[])
    ax.set(title="(c) HNN-conserved quantity", xlabel=xlabel,
           ylabel=r"learned $H_\theta(t) - H_\theta(t_0)$ along the HNN rollout" "\n"
           "(H is defined only up to a constant)" if drift
           else r"learned $H_\theta$ + constant, along the HNN rollout")


def learned_h_shift(h, truth):
    """The constant that makes the learned H equal the true energy at the shown rollout's first
    state (where the rollout starts from the true state): H is defined only up to a constant.
    0 without a true energy there."""
    e0 = truth["true_energy"][0] if len(truth["true_energy"]) else np.nan
    return float(e0 - h[0]) if np.isfinite(e0) and np.isfinite(h[0]) else 0.0


def phase_axes(d, metrics):
    """((i, j), (q_1's label, p_1's label), the positions' names) for a state (q_1..q_n,
    p_1..p_n): q_1 and p_1 are its columns i and j; names from metrics.json's "state_names" if
    it has d of them, else q/p (d = 2) or q1/p1 and q1..qn."""
    n = d // 2 if d % 2 == 0 else 1
    names = ("position q", "momentum p") if d == 2 else ("q1", "p1")
    positions = "q" if n == 1 else f"q1..q{n}"
    state_names = setting(metrics, "state_names")
    if isinstance(state_names, list) and len(state_names) == d:
        names = (str(state_names[0]), str(state_names[n]))
        positions = ", ".join(map(str, state_names[:n]))
    elif state_names is not None:
        note(f"metrics.json: state_names {state_names!r} is not a list of {d} names, ignored")
    return (0, n), names, positions


def run_labels(runs):
    """{model: legend text}: the model's name, with metrics.json's valid_prediction_time and
    coordinate_mse (data runs) when it has them; for a run marked "of_file" (an `hnn rollout`
    file), the valid prediction time of the file's own rollouts instead."""
    labels = {}
    for model in MODELS:
        run = runs.get(model) or {}
        metrics = run.get("metrics") or {}
        if run.get("of_file"):
            threshold = metrics.get("valid_prediction_threshold")
            roll = run["rollout"]
            time = roll.valid_prediction_time(threshold if is_number(threshold) else 0.1)
            labels[model] = (f"{LABELS[model]}\nvalid pred. time {time:.3g}"
                             f" (these {len(roll.trajs)} rollouts)")
            continue
        parts = [f"{text} {metrics[key]:{form}}" for key, text, form in
                 (("valid_prediction_time", "valid pred. time", ".3g"),
                  ("coordinate_mse", "coord. MSE", ".2e"))
                 if is_number(metrics.get(key))]
        labels[model] = LABELS[model] + ("\n" + ", ".join(parts) if parts else "")
    return labels


def draw_fig2(results, task, runs, rolls, truth, title=None, stem=None):
    """Paper Figure 2 row: (a) phase space, (b) coordinate MSE, (c) HNN-conserved quantity,
    (d) total energy, all for one test trajectory (the rollouts' `show`, 0 unless set) except
    (b), which covers all rollouts. A state of n > 1 degrees of freedom shows q_1 against p_1 in
    (a). Without a true energy (runs of data with no known Hamiltonian) (c) is the drift of the
    learned H and there is no (d). The data task's (b) compares the positions alone, as its
    metrics.json's coordinate_mse does. The files are <stem> (default fig2_<task>).png and
    .svg."""
    metrics = next((runs[m]["metrics"] for m in MODELS if runs.get(m) and runs[m]["metrics"]),
                   {})
    coords, names, positions = phase_axes(truth["true"].shape[1], metrics)
    energy = np.any(np.isfinite(truth["true_energy"]))
    fig, axes = plt.subplots(1, 4 if energy else 3, figsize=(17, 4.2) if energy else (13, 4.2),
                             layout="constrained")
    plot_phase_panel(axes[0], rolls, truth, coords, names)
    if coords != (0, 1):
        axes[0].set_title(f"(a) Predictions (phase space of {names[0]}, {names[1]})")
    if task == "data":  # its metrics.json's coordinate_mse compares the positions q alone
        plot_mse_panel(axes[1], rolls, run_labels(runs), columns=slice(0, coords[1]))
        axes[1].set_title(f"(b) MSE between coordinates ({positions})")
    else:
        plot_mse_panel(axes[1], rolls, run_labels(runs))
        axes[1].set_title("(b) MSE between coordinates")
    plot_learned_h_panel(axes[2], rolls, truth, drift=not energy,
                         spread=learned_h_spread((runs.get("hnn") or {}).get("metrics") or {}))
    if energy:
        plot_energy_panel(axes[3], rolls, truth)
        axes[3].set_title("(d) Total energy")
    else:
        axes[2].set_title("(c) Energy: drift of the learned H only\n"
                          "(no known Hamiltonian, so no true energy)")
    t, roll = truth["t"], next(iter(rolls.values()))
    which = f"test trajectory {roll.show}"
    if roll.uneven():
        which += f" (the longest of {len(roll.trajs)})"
    fig.suptitle(f"{title or TITLES.get(task, task)}: {which}, t = {t[0]:g}..{t[-1]:g}"
                 f"{energy_summary(runs)}")
    return save(fig, results, stem or f"fig2_{task}")
