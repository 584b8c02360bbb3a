#!/usr/bin/python3
"""Renders every chart of an hnn results folder to PNG and SVG (matplotlib, Agg).

Usage: /usr/bin/python3 scripts/plot.py RESULTS_DIR
       /usr/bin/python3 scripts/plot.py --runs RUN [RUN ...] --out DIR

Reads RESULTS_DIR/table1.json and RESULTS_DIR/<task>/<model>/{metrics.json,loss_curve.csv,
rollout.csv} as written by `hnn reproduce`, and writes into RESULTS_DIR:
  fig2_<task>       2-D tasks: phase space, coordinate MSE, HNN-conserved quantity, energy
  fig3_<task>       n-body tasks: orbits (truth / baseline / HNN), coordinate MSE, energy
  training_curves   train and test loss vs step, one panel per task
  table1_chart      test loss and energy MSE, ours vs the paper's Table 1
Missing tasks, models or files are skipped with a one-line note on stderr; a file that cannot
be parsed is an error naming it (exit code 1). Each written file's path goes to stdout.

--runs draws Figure 2 of any run folders (`hnn train ... --out RUN`, e.g. of the `data` task),
at most one per model and all of one task and the same held-out data, into DIR/fig2_<task>:
q_1 against p_1 (names from metrics.json's "state_names"), the coordinate MSE against the time
since each rollout's start, and the energies; without a known Hamiltonian (empty true_energy)
the last panel is the drift of the HNN's learned H along its own rollout. A run that lacks
metrics.json or rollout.csv, or runs of different tasks or data, are an error naming them.
"""

import argparse
import csv
import json
import math
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

TASKS = ["spring", "pendulum", "real-pendulum", "two-body", "three-body", "pixel-pendulum"]
TITLES = {"spring": "Ideal mass-spring", "pendulum": "Ideal pendulum",
          "real-pendulum": "Real pendulum", "two-body": "Two-body", "three-body": "Three-body",
          "pixel-pendulum": "Pixel pendulum"}
MODELS = ["baseline", "hnn"]
COLORS = {"truth": "black", "baseline": "tab:red", "hnn": "tab:blue"}
LABELS = {"truth": "Ground truth", "baseline": "Baseline NN", "hnn": "Hamiltonian NN"}
FRAME_ROLLOUTS = {"pixel-pendulum"}  # rollouts of frames: Figure 4 in plot_pixel.py
UMASK = os.umask(0o022)
os.umask(UMASK)

plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "hnn", "font.size": 9,
                     "axes.titlesize": 10, "legend.fontsize": 8})


class PlotError(Exception):
    """A results file exists but cannot be used; the message names the file."""


def note(message):
    print(f"plot.py: note: {message}", file=sys.stderr)


# ---------------------------------------------------------------------------------------------
# Reading


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise PlotError(f"{path}: not valid JSON: {e}") from e


def to_float(cell, path, line, column):
    """A CSV cell as a float; an empty cell is NaN (e.g. learned_h of the baseline)."""
    cell = cell.strip()
    if cell == "":
        return math.nan
    try:
        return float(cell)
    except ValueError:
        raise PlotError(f"{path}:{line}: column '{column}': not a number: {cell!r}") from None


def read_csv(path, required):
    """Reads a numeric CSV with a header into {column: np.ndarray}. Checks the required columns
    and that every row has as many cells as the header."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (csv.Error, UnicodeDecodeError) as e:
        raise PlotError(f"{path}: not a readable CSV: {e}") from e
    if not rows:
        raise PlotError(f"{path}: empty file (expected a header)")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in required if c not in header]
    if missing:
        raise PlotError(f"{path}: header lacks column(s) {', '.join(missing)};"
                        f" got {','.join(header)}")
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise PlotError(f"{path}:{line}: {len(row)} cells, header has {len(header)}")
        values.append([to_float(c, path, line, h) for c, h in zip(row, header)])
    if not values:
        raise PlotError(f"{path}: no data rows")
    table = np.array(values, dtype=float)
    return {h: table[:, i] for i, h in enumerate(header)}


class Rollout:
    """rollout.csv of one model: per-trajectory time, true and predicted states and energies."""

    def __init__(self, path):
        cols = read_csv(path, ["traj", "t", "true_energy", "pred_energy", "learned_h"])
        d = sum(1 for h in cols if h.startswith("true_") and h != "true_energy")
        state = [f"true_{i}" for i in range(d)] + [f"pred_{i}" for i in range(d)]
        missing = [c for c in state if c not in cols]
        if d == 0 or missing:
            raise PlotError(f"{path}: header needs true_0..true_{{d-1}} and pred_0..pred_{{d-1}};"
                            f" got {','.join(cols)}")
        for key in ("traj", "t"):
            if not np.all(np.isfinite(cols[key])):
                raise PlotError(f"{path}: column '{key}' has empty or non-finite cells")
        self.path, self.d = path, d
        self.show = 0  # the trajectory of the single-trajectory panels
        self.trajs = []
        for k in np.unique(cols["traj"]):
            rows = cols["traj"] == k
            order = np.argsort(cols["t"][rows], kind="stable")
            pick = {name: cols[name][rows][order] for name in cols}
            self.trajs.append({"t": pick["t"],
                               "true": np.stack([pick[f"true_{i}"] for i in range(d)], axis=1),
                               "pred": np.stack([pick[f"pred_{i}"] for i in range(d)], axis=1),
                               "true_energy": pick["true_energy"],
                               "pred_energy": pick["pred_energy"],
                               "learned_h": pick["learned_h"]})

    @property
    def shown(self):
        """The trajectory that the phase-space and energy panels show."""
        return self.trajs[self.show]

    def mse_by_trajectory(self, columns=slice(None)):
        """[(tau, mse)] per trajectory: tau = time since the trajectory's first time, mse = mean
        over the state's components (those of `columns`) of (pred - true)^2."""
        return [(tr["t"] - tr["t"][0],
                 np.mean((tr["pred"][:, columns] - tr["true"][:, columns]) ** 2, axis=1))
                for tr in self.trajs]

    def uneven(self):
        """Whether the trajectories differ in start time or length (held-out measured data)."""
        return len({(tr["t"][0], len(tr["t"])) for tr in self.trajs}) > 1

    def coordinate_mse(self, columns=slice(None)):
        """(tau, mse(tau), count) against the time since each trajectory's start: the mean over
        the `count` trajectories that are still running at tau of the mean over components (of
        `columns`) of (pred - true)^2. None when the trajectories are not sampled alike (each
        one's tau must be the start of the longest one's, within 1% of a step), as a mean at a
        time only some of them were measured at would mislead."""
        per = self.mse_by_trajectory(columns)
        longest = max((tau for tau, _ in per), key=len)
        step = np.median(np.diff(longest)) if len(longest) > 1 else 0.0
        if not all(np.allclose(tau, longest[:len(tau)], rtol=0.0, atol=0.01 * step)
                   for tau, _ in per):
            return None
        total, count = np.zeros(len(longest)), np.zeros(len(longest))
        for _, mse in per:
            total[:len(mse)] += mse
            count[:len(mse)] += 1
        return longest, total / count, count


def load_model(task_dir, task, model):
    """{'metrics', 'loss', 'rollout'} for one model; a missing file gives None (with a note)."""
    model_dir = os.path.join(task_dir, model)
    if not os.path.isdir(model_dir):
        note(f"{task}/{model}: missing, skipped")
        return None
    run = {}
    readers = {"metrics": ("metrics.json", read_json),
               "loss": ("loss_curve.csv",
                        lambda p: read_csv(p, ["step", "train_loss", "test_loss"])),
               "rollout": ("rollout.csv", Rollout)}
    for key, (name, reader) in readers.items():
        path = os.path.join(model_dir, name)
        if os.path.isfile(path):
            run[key] = reader(path)
        else:
            run[key] = None
            note(f"{task}/{model}/{name}: missing, skipped")
    if run["metrics"] is not None and not isinstance(run["metrics"], dict):
        raise PlotError(f"{os.path.join(model_dir, 'metrics.json')}: expected a JSON object")
    return run


def find_tasks(results):
    """Known tasks in paper order, then any other folder holding a model folder."""
    extra = sorted(n for n in os.listdir(results) if n not in TASKS and any(
        os.path.isdir(os.path.join(results, n, m)) for m in MODELS))
    return TASKS + extra


def read_table1(results):
    path = os.path.join(results, "table1.json")
    if not os.path.isfile(path):
        note("table1.json: missing, Table 1 chart skipped")
        return None
    rows = read_json(path)
    if not isinstance(rows, list) or not all(
            isinstance(r, dict) and "task" in r and "model" in r for r in rows):
        raise PlotError(f"{path}: expected a list of objects with 'task' and 'model' keys")
    numeric = ("train_loss", "train_loss_se", "test_loss", "test_loss_se", "energy_mse",
               "energy_mse_se", "train_seconds", "paper_train_loss", "paper_test_loss",
               "paper_energy_mse")
    for r in rows:
        for key in numeric:
            value = r.get(key)
            if value is not None and not isinstance(value, (int, float)):
                raise PlotError(f"{path}: {r['task']}/{r['model']}: '{key}' is not a number")
    return rows


# ---------------------------------------------------------------------------------------------
# Drawing helpers


def save(fig, results, stem, **savefig_options):
    """Writes stem.png and stem.svg atomically (temp file in the same folder, then rename).
    savefig_options go to matplotlib (e.g. bbox_inches="tight")."""
    written = []
    for ext in ("png", "svg"):
        final = os.path.join(results, f"{stem}.{ext}")
        fd, tmp = tempfile.mkstemp(dir=results, prefix=f".{stem}.", suffix=f".{ext}.tmp")
        os.close(fd)
        try:
            fig.savefig(tmp, format=ext, dpi=150,  # no date in the SVG: same data, same bytes
                        metadata={"Date": None} if ext == "svg" else None, **savefig_options)
            os.chmod(tmp, 0o666 & ~UMASK)  # mkstemp makes 0600; give the usual permissions
            os.replace(tmp, final)
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
        written.append(final)
        print(final)
    plt.close(fig)
    return written


def log_y_if_positive(ax, *series):
    """Log y axis when some value is positive (zeros, e.g. the MSE at t=0, are masked)."""
    if any(np.any(np.asarray(s)[np.isfinite(s)] > 0) for s in series):
        ax.set_yscale("log")


def clamp_limits(reference, everything, margin=0.5, min_span=0.0):
    """Axis limits covering `everything`, but reaching at most `margin` reference spans beyond
    the reference range, so a diverging model cannot squash the ground truth into a dot. The
    span is at least `min_span`, so a conserved quantity plots as a flat line instead of
    magnified round-off."""
    ref = np.asarray(reference, dtype=float)
    ref = ref[np.isfinite(ref)]
    allv = np.asarray(everything, dtype=float)
    allv = np.concatenate([ref, allv[np.isfinite(allv)]])
    if ref.size == 0:
        return None
    lo, hi = ref.min(), ref.max()
    scale = max(abs(lo), abs(hi))
    span = max(hi - lo, min_span, 1e-9 * scale, 1e-12)
    mid = 0.5 * (lo + hi)
    lo, hi = min(lo, mid - span / 2), max(hi, mid + span / 2)
    lo, hi = max(allv.min(), lo - margin * span), min(allv.max(), hi + margin * span)
    lo, hi = min(lo, mid - span / 2), max(hi, mid + span / 2)
    return lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)


def energy_scale(truth):
    """The smallest y span of energy-like panels: 20% of the true energy's magnitude. The learned
    H has the true energy's gradient, so it equals the energy up to a constant: same scale."""
    energy = truth["true_energy"][np.isfinite(truth["true_energy"])]
    return 0.2 * np.max(np.abs(energy)) if energy.size else 0.0


def set_limits(setter, limits):
    if limits is not None:
        setter(*limits)


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def setting(metrics, key):
    """metrics.json's `key`, at its top level (where `hnn train` puts its settings) or in a
    "settings" object."""
    if key in metrics:
        return metrics[key]
    settings = metrics.get("settings")
    return settings.get(key) if isinstance(settings, dict) else None


def energy_summary(runs):
    """' (energy MSE: baseline 1.7e-01, HNN 3.8e-04)' from metrics.json, or ''."""
    parts = []
    for model in MODELS:
        metrics = (runs.get(model) or {}).get("metrics") or {}
        if is_number(metrics.get("energy_mse")):
            parts.append(f"{'HNN' if model == 'hnn' else model} {metrics['energy_mse']:.2e}")
    return f" (energy MSE: {', '.join(parts)})" if parts else ""


def rollouts_of(runs):
    """{model: Rollout} for the models that have one, and the ground truth of the trajectory they
    show (0 unless set)."""
    rolls = {m: runs[m]["rollout"] for m in MODELS if runs.get(m) and runs[m]["rollout"]}
    truth = (rolls.get("hnn") or rolls.get("baseline")).shown
    if len(rolls) == 2 and not same_truth(rolls["baseline"].shown, truth):
        note(f"{rolls['hnn'].path}: trajectory {rolls['hnn'].show} has another ground truth than"
             " the baseline's; the charts use the HNN's")
    return rolls, truth


def same_truth(a, b):
    """Whether two rollouts start from the same ground truth (same initial state and grid)."""
    n = min(len(a["t"]), len(b["t"]))
    return np.allclose(a["t"][:n], b["t"][:n]) and np.allclose(
        a["true"][:n], b["true"][:n], rtol=1e-6, atol=1e-9, equal_nan=True)


def plot_mse_panel(ax, rolls, labels=None, columns=slice(None)):
    """Coordinate MSE against the time since each rollout's start. Rollouts of one length and
    start (the generated tasks): their mean. Uneven ones (held-out measured stretches of several
    lengths): each rollout as a thin line, and in bold the mean over those still running, for as
    long as at least half of them are (later it would follow a few stretches' noise, which the
    thin lines show anyway); if their sampling times differ, the thin lines alone, as a mean
    would mix rollouts measured at different times. The y range leaves out the start, where a
    rollout equals the measured state up to round-off. labels: {model: legend text}; columns:
    the state's components to compare (all by default)."""
    curves, later, uneven, no_mean, start_off = [], [], False, False, False
    for model, roll in rolls.items():
        label = (labels or {}).get(model, LABELS[model])
        mean = roll.coordinate_mse(columns)
        per = roll.mse_by_trajectory(columns)
        if roll.uneven() or mean is None:
            uneven = True
            alpha = 0.8 if mean is None else max(0.15, min(0.45, 6 / len(per)))
            for k, (tau, mse) in enumerate(per):
                ax.plot(tau, mse, color=COLORS[model], lw=1.0 if mean is None else 0.6,
                        alpha=alpha, label=label if mean is None and k == 0 else None)
                curves.append(mse)
        later += [mse[tau > 0] for tau, mse in per]
        start_off |= any(np.any(mse[tau == 0] > 0) for tau, mse in per)
        if mean is None:
            no_mean = True
            continue
        tau, mse, count = mean
        if roll.uneven():
            tau, mse = tau[count >= len(per) / 2], mse[count >= len(per) / 2]
        ax.plot(tau, mse, color=COLORS[model], label=label)
        curves.append(mse)
    log_y_if_positive(ax, *curves)
    later = np.concatenate(later)
    later = later[np.isfinite(later) & (later > 0)]
    if start_off and later.size and ax.get_yscale() == "log":
        ax.set_ylim(bottom=later.min() / 3)
    starts = {tr["t"][0] for roll in rolls.values() for tr in roll.trajs}
    ylabel = "mean squared error (all test rollouts)"
    if no_mean:
        ylabel = "mean squared error of each rollout\n(sampled at different times: no mean)"
    elif uneven:
        ylabel = "mean squared error (thin: each rollout;\nbold: mean while half or more run)"
    ax.set(title="MSE between coordinates", ylabel=ylabel,
           xlabel="time t" if starts == {0.0} else "time since the rollout's start")
    ax.legend()


def time_axis(t):
    """(x, label) of a time axis: t itself from t = 0, else the time since t[0] (shorter ticks)."""
    return (t, "time t") if t[0] == 0 else (t - t[0], f"time since t = {t[0]:g}")


def plot_energy_panel(ax, rolls, truth):
    t, xlabel = time_axis(truth["t"])
    ax.plot(t, truth["true_energy"], color=COLORS["truth"], label=LABELS["truth"])
    for model, roll in rolls.items():
        tr = roll.shown
        ax.plot(time_axis(tr["t"])[0], tr["pred_energy"], color=COLORS[model],
                label=LABELS[model])
    series = [truth["true_energy"]] + [r.shown["pred_energy"] for r in rolls.values()]
    set_limits(ax.set_ylim, clamp_limits(truth["true_energy"], np.concatenate(series),
                                         margin=3.0, min_span=energy_scale(truth)))
    ax.set(title="Total energy", xlabel=xlabel, ylabel="true energy E of the state")
    ax.legend()


# ---------------------------------------------------------------------------------------------
# Charts


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
            ax.plot(t, h, color=COLORS["hnn"], label=LABELS["hnn"])
            set_limits(ax.set_ylim, clamp_limits(h, h, min_span=energy_scale(truth)))
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
           ylabel=r"learned $H_\theta(t) - H_\theta(t_0)$ along the HNN rollout" if drift
           else r"learned $H_\theta$ along the HNN rollout")


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
    coordinate_mse (data runs) when it has them."""
    labels = {}
    for model in MODELS:
        metrics = (runs.get(model) or {}).get("metrics") or {}
        parts = [f"{text} {metrics[key]:{form}}" for key, text, form in
                 (("valid_prediction_time", "valid pred. time", ".3g"),
                  ("coordinate_mse", "coord. MSE", ".2e"))
                 if is_number(metrics.get(key))]
        labels[model] = LABELS[model] + ("\n" + ", ".join(parts) if parts else "")
    return labels


def draw_fig2(results, task, runs, rolls, truth, title=None):
    """Paper Figure 2 row: (a) phase space, (b) coordinate MSE, (c) HNN-conserved quantity,
    (d) total energy, all for one test trajectory (the rollouts' `show`, 0 unless set) except
    (b), which covers all rollouts. A state of n > 1 degrees of freedom shows q_1 against p_1 in
    (a). Without a true energy (runs of data with no known Hamiltonian) (c) is the drift of the
    learned H and there is no (d). The data task's (b) compares the positions alone, as its
    metrics.json's coordinate_mse does."""
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
    return save(fig, results, f"fig2_{task}")


def plot_orbits(ax, t, states, n_bodies, color, limits, title):
    """x vs y of every body; states columns are (qx1..qxn, qy1..qyn, px.., py..). Says so when
    the orbit leaves the shared frame or the state stops being finite."""
    styles = ["-", "--", ":", "-."]
    for b in range(n_bodies):
        x, y = states[:, b], states[:, n_bodies + b]
        alpha = 1.0 - 0.55 * b / max(n_bodies - 1, 1)  # later bodies lighter, and dashed
        ax.plot(x, y, styles[b % 4], color=color, alpha=alpha, lw=1.3, label=f"body {b + 1}")
        ax.plot(x[0], y[0], "o", color=color, alpha=alpha, ms=4)
    positions = states[:, :2 * n_bodies]
    finite = np.all(np.isfinite(positions), axis=1)
    remarks = []
    if np.any((positions[finite] < limits[0]) | (positions[finite] > limits[1])):
        remarks.append("leaves the frame")
    if not np.all(finite):
        remarks.append(f"not finite from t = {t[np.argmin(finite)]:.3g}")
    if remarks:
        ax.text(0.03, 0.03, "; ".join(remarks), transform=ax.transAxes, fontsize=7,
                style="italic", color=color)
    ax.set_xlim(*limits)
    ax.set_ylim(*limits)
    ax.set_aspect("equal")
    ax.set(title=title, xlabel="x", ylabel="y")
    ax.legend(loc="upper right")


def draw_fig3(results, task, runs, rolls, truth):
    """Paper Figure 3: orbits of test trajectory 0 (truth, baseline, HNN on equal axes), the
    coordinate MSE over all test rollouts, and total energy of trajectory 0."""
    n_bodies = truth["true"].shape[1] // 4
    pos = slice(0, 2 * n_bodies)
    every = np.concatenate([truth["true"][:, pos]] + [r.shown["pred"][:, pos]
                                                       for r in rolls.values()])
    limits = clamp_limits(truth["true"][:, pos], every, margin=0.5) or (-1.0, 1.0)
    fig, axes = plt.subplots(1, 5, figsize=(20, 4.2), layout="constrained",
                             gridspec_kw={"width_ratios": [1, 1, 1, 1.25, 1.25]})
    plot_orbits(axes[0], truth["t"], truth["true"], n_bodies, COLORS["truth"], limits,
                LABELS["truth"])
    for ax, model in zip(axes[1:3], MODELS):
        if model in rolls:
            tr = rolls[model].shown
            plot_orbits(ax, tr["t"], tr["pred"], n_bodies, COLORS[model], limits, LABELS[model])
        else:
            ax.set_title(LABELS[model])
            ax.text(0.5, 0.5, "no rollout", ha="center", transform=ax.transAxes)
    plot_mse_panel(axes[3], rolls)
    plot_energy_panel(axes[4], rolls, truth)
    t_end = truth["t"][-1]
    fig.suptitle(f"{TITLES.get(task, task)}: test trajectory 0, t = 0..{t_end:g}"
                 f"{energy_summary(runs)}")
    return save(fig, results, f"fig3_{task}")


def draw_training_curves(results, all_runs):
    """One panel per task: train (solid) and test (dashed) loss vs step, baseline and HNN."""
    tasks = [t for t, runs in all_runs.items()
             if any(runs.get(m) and runs[m]["loss"] is not None for m in MODELS)]
    if not tasks:
        note("no loss_curve.csv found, training curves skipped")
        return []
    cols = min(3, len(tasks))
    rows = math.ceil(len(tasks) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.6 * rows), layout="constrained",
                             squeeze=False)
    for ax, task in zip(axes.flat, tasks):
        curves = []
        for model in MODELS:
            loss = (all_runs[task].get(model) or {}).get("loss")
            if loss is None:
                continue
            for split, style in (("train", "-"), ("test", "--")):
                y = loss[f"{split}_loss"]
                ok = np.isfinite(y)
                ax.plot(loss["step"][ok], y[ok], style, color=COLORS[model],
                        label=f"{LABELS[model]}, {split}")
                curves.append(y)
        log_y_if_positive(ax, *curves)
        ylabel = "loss: ae + cc + 0.1 hnn" if task == "pixel-pendulum" else "loss: MSE of dx/dt"
        ax.set(title=TITLES.get(task, task), xlabel="training step", ylabel=ylabel)
        ax.legend()
    for ax in list(axes.flat)[len(tasks):]:
        ax.set_visible(False)
    fig.suptitle("Training curves: train (solid) and test (dashed) loss")
    return save(fig, results, "training_curves")


TABLE1_BARS = [("baseline", "ours"), ("baseline", "paper"), ("hnn", "ours"), ("hnn", "paper")]


def table1_index(rows):
    """{(task, model): row} and the tasks in paper order."""
    by_key = {}
    for r in rows:
        if (r["task"], r["model"]) in by_key:
            note(f"table1.json: duplicate entry {r['task']}/{r['model']}, using the last")
        by_key[(r["task"], r["model"])] = r
    tasks = [t for t in TASKS if any((t, m) in by_key for m in MODELS)]
    return by_key, tasks + sorted({r["task"] for r in rows} - set(tasks))


def table1_bar(by_key, tasks, metric, model, source):
    """Bar heights and [lower, upper] standard-error bars (ours only; the lower bar is cut so
    that it stays above zero on the log axis). Missing or non-positive values are NaN."""
    prefix = "paper_" if source == "paper" else ""
    heights, lower, upper = [], [], []
    for task in tasks:
        r = by_key.get((task, model), {})
        v = r.get(prefix + metric)
        ok = isinstance(v, (int, float)) and v > 0
        se = r.get(metric + "_se") if source == "ours" and ok else None
        se = se if isinstance(se, (int, float)) else 0.0
        heights.append(v if ok else np.nan)
        lower.append(min(se, 0.9 * v) if ok else 0.0)
        upper.append(se)
    return np.array(heights), [lower, upper]


def draw_table1_chart(results, rows):
    """Grouped log bars per task: ours (solid, standard-error bars) vs the paper (hatched, light),
    baseline and HNN; one panel for test loss, one for energy MSE."""
    by_key, tasks = table1_index(rows)
    if not tasks:
        note("table1.json: no rows, Table 1 chart skipped")
        return []
    fig, axes = plt.subplots(1, 2, figsize=(max(10, 2.6 * len(tasks) + 2), 4.8),
                             layout="constrained")
    x, width = np.arange(len(tasks)), 0.2
    for ax, (metric, label) in zip(axes, (("test_loss", "test loss (MSE of dx/dt)"
                                           + ("; pixels: ae+cc+0.1hnn" if "pixel-pendulum"
                                              in tasks else "")),
                                          ("energy_mse", "energy MSE"))):
        tops = []
        for i, (model, source) in enumerate(TABLE1_BARS):
            heights, err = table1_bar(by_key, tasks, metric, model, source)
            paper = source == "paper"
            bars = ax.bar(x + (i - 1.5) * width, heights, width, log=True,
                          yerr=None if paper else err, capsize=2, color=COLORS[model],
                          alpha=0.4 if paper else 0.95, hatch="//" if paper else None,
                          edgecolor="white", label=f"{LABELS[model]} ({source})")
            ax.bar_label(bars, labels=["" if np.isnan(h) else f"{h:.1e}" for h in heights],
                         rotation=90, fontsize=6, padding=2 if paper else 7)
            tops.append(heights)
        finite = np.concatenate(tops)
        finite = finite[np.isfinite(finite)]
        if finite.size:  # room above the tallest bar for its label and the legend
            ax.set_ylim(finite.min() / 5, finite.max() * 1e3)
        ax.set_xticks(x, [TITLES.get(t, t) for t in tasks])
        ax.set(title=f"{label}: ours vs the paper's Table 1", ylabel=f"{label}, log scale")
        ax.grid(axis="y", which="major", alpha=0.3)
        ax.legend(ncols=2, loc="upper right", fontsize=7)
    return save(fig, results, "table1_chart")


# ---------------------------------------------------------------------------------------------


def draw_rollout_charts(results, task, runs):
    """fig2 for a 2-D state, fig3 for n bodies in the plane (d = 4n)."""
    if not any(runs.get(m) and runs[m]["rollout"] for m in MODELS):
        note(f"{task}: no rollout.csv, rollout charts skipped")
        return []
    if task in FRAME_ROLLOUTS:
        return []  # scripts/plot_pixel.py draws them
    rolls, truth = rollouts_of(runs)
    d = truth["true"].shape[1]
    if d == 2:
        return draw_fig2(results, task, runs, rolls, truth)
    if d % 4 == 0:
        return draw_fig3(results, task, runs, rolls, truth)
    note(f"{task}: state dimension {d} has no chart, skipped")
    return []


def plot_all(results):
    """Reads every input first (so a malformed file stops the run before anything is written),
    then draws every chart the folder supports; returns the list of files written."""
    all_runs = {}
    for task in find_tasks(results):
        task_dir = os.path.join(results, task)
        if not os.path.isdir(task_dir):
            note(f"{task}: no results, skipped")
            continue
        all_runs[task] = {m: load_model(task_dir, task, m) for m in MODELS}
    table1 = read_table1(results)
    written = []
    for task, runs in all_runs.items():
        written += draw_rollout_charts(results, task, runs)
    written += draw_training_curves(results, all_runs)
    if table1 is not None:
        written += draw_table1_chart(results, table1)
    return written


# ---------------------------------------------------------------------------------------------
# --runs: Figure 2 of run folders


def load_run(folder):
    """{'folder', 'task', 'model', 'metrics', 'loss', 'rollout'} of one `hnn train` run folder;
    a missing or unusable file is an error naming it."""
    if not os.path.isdir(folder):
        raise PlotError(f"{folder}: not a folder")
    run = {"folder": folder, "loss": None}
    for key, name, reader in (("metrics", "metrics.json", read_json),
                              ("rollout", "rollout.csv", Rollout)):
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            raise PlotError(f"{path}: missing (is {folder} a finished run folder?)")
        run[key] = reader(path)
        if key == "metrics" and not isinstance(run["metrics"], dict):
            raise PlotError(f"{path}: expected a JSON object")
    for key in ("task", "model"):
        value = setting(run["metrics"], key)
        if not isinstance(value, str) or not value:
            raise PlotError(f"{os.path.join(folder, 'metrics.json')}: no '{key}' setting")
        run[key] = value
    if run["model"] not in MODELS:
        raise PlotError(f"{os.path.join(folder, 'metrics.json')}: model '{run['model']}' is not"
                        f" one of {', '.join(MODELS)}")
    return run


def check_runs(loaded):
    """Raises unless the runs are of one task and the same held-out data, at most one per model:
    the same trajectories at the same times with the same true states."""
    tasks = {run["task"] for run in loaded}
    if len(tasks) > 1:
        raise PlotError("runs of different tasks: " + ", ".join(
            f"{run['folder']} ({run['task']})" for run in loaded))
    by_model = {}
    for run in loaded:
        if run["model"] in by_model:
            raise PlotError(f"two {run['model']} runs: {by_model[run['model']]['folder']} and"
                            f" {run['folder']}; give at most one run per model")
        by_model[run["model"]] = run
    first = loaded[0]
    for run in loaded[1:]:
        a, b = first["rollout"].trajs, run["rollout"].trajs
        same = len(a) == len(b) and all(
            len(x["t"]) == len(y["t"]) and np.allclose(x["t"], y["t"], rtol=1e-9, atol=0.0)
            and np.allclose(x["true"], y["true"], rtol=1e-6, atol=1e-9 * max(
                1.0, float(np.nanmax(np.abs(x["true"]), initial=0.0))), equal_nan=True)
            for x, y in zip(a, b))
        if not same:
            files = [setting(r["metrics"], "data_file") for r in (first, run)]
            detail = (f" (data files {files[0]!r} and {files[1]!r})" if files[0] != files[1]
                      else "")
            raise PlotError(f"runs of different data: {first['folder']} and {run['folder']} hold"
                            f" different test trajectories in rollout.csv{detail}")
    return by_model


def run_title(task, runs):
    """The figure's title: the task's, or for the data task the data file's name."""
    if task != "data":
        return TITLES.get(task, task)
    files = {setting(r["metrics"], "data_file") for r in runs.values()}
    files = sorted(os.path.basename(f) for f in files if isinstance(f, str) and f)
    return f"Data from {', '.join(files)}" if files else "Data"


def plot_runs(folders, out):
    """Figure 2 of the given run folders into out/fig2_<task>; returns the files written."""
    loaded = [load_run(folder) for folder in folders]
    runs = check_runs(loaded)
    task = loaded[0]["task"]
    if task in FRAME_ROLLOUTS:
        raise PlotError(f"{task}: rollouts of frames; scripts/plot_pixel.py draws them")
    os.makedirs(out, exist_ok=True)
    trajs = loaded[0]["rollout"].trajs  # the longest shows most: the first of one length
    show = max(range(len(trajs)), key=lambda k: (trajs[k]["t"][-1] - trajs[k]["t"][0], -k))
    for run in loaded:
        run["rollout"].show = show
    rolls, truth = rollouts_of(runs)
    return draw_fig2(out, task, runs, rolls, truth, title=run_title(task, runs))


def usage():
    print("\n".join(__doc__.strip().splitlines()[2:4]), file=sys.stderr)
    return 2


def main(argv):
    if "--runs" in argv[1:]:
        parser = argparse.ArgumentParser(prog="plot.py", description="Figure 2 of run folders")
        parser.add_argument("--runs", nargs="+", required=True, metavar="RUN")
        parser.add_argument("--out", required=True, metavar="DIR")
        args = parser.parse_args(argv[1:])
        try:
            plot_runs(args.runs, args.out)
        except (PlotError, OSError) as e:
            print(f"plot.py: error: {e}", file=sys.stderr)
            return 1
        return 0
    if len(argv) != 2:
        return usage()
    results = argv[1]
    if not os.path.isdir(results):
        print(f"plot.py: error: {results}: not a folder", file=sys.stderr)
        return 1
    try:
        written = plot_all(results)
    except PlotError as e:
        print(f"plot.py: error: {e}", file=sys.stderr)
        return 1
    if not written:
        note(f"{results}: nothing to draw")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
