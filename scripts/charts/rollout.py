"""rollout.csv of `hnn train` and `hnn reproduce`, and the rollout_<integrator>.csv of `hnn
rollout` (per test trajectory: time, true and predicted states, energies, the HNN's learned H),
and the panels that Figures 2 and 3 share: the coordinate MSE against time and the total
energy."""


import numpy as np

from .common import COLORS, LABELS, MODELS, PlotError, is_number, note, read_csv

def truth_at(truth, t):
    """The truth's columns (a dict of arrays over its own times) at the times t: linear
    interpolation between its samples, NaN outside their span (a measured stretch may end before
    the model's rollout does)."""
    inside = (t >= truth["t"][0] - 1e-9 * abs(truth["t"][-1])) & \
        (t <= truth["t"][-1] * (1 + 1e-12))
    out = {"t": t}
    for name, values in truth.items():
        if name != "t":
            out[name] = np.full(len(t), np.nan)
            out[name][inside] = np.interp(t[inside], truth["t"], values)
    return out


# rollout.csv's columns besides the state's (tasks/report/rollout_csv.h), and the sources that
# are the truth: the true system integrated, or measured data.
META = ("source", "traj", "t", "energy", "learned_h")
TRUTHS = ("true", "data")


class Rollout:
    """rollout.csv of one model: per trajectory the time, the true and predicted states and
    energies, the learned H. The file holds a block of rows per source (the truth, "true" or
    "data", and the model) and trajectory, at the same times; `names` are the state's columns."""

    def __init__(self, path):
        cols = read_csv(path, META, text=("source",))
        names = [h for h in cols if h not in META]
        sources = list(dict.fromkeys(cols["source"]))
        truths = [s for s in sources if s in TRUTHS]
        models = [s for s in sources if s not in TRUTHS]
        if not names or len(truths) != 1 or len(models) != 1:
            raise PlotError(f"{path}: a rollout.csv has state columns between t and energy and"
                            f" the rows of one truth ({' or '.join(TRUTHS)}) and one model;"
                            f" got columns {','.join(cols)} and sources {','.join(sources)}")
        for key in ("traj", "t"):
            if not np.all(np.isfinite(cols[key])):
                raise PlotError(f"{path}: column '{key}' has empty or non-finite cells")
        self.path, self.d, self.names, self.model = path, len(names), names, models[0]
        self.show = 0  # the trajectory of the single-trajectory panels
        self.trajs = []
        moved = 0
        for k in np.unique(cols["traj"]):
            truth, pred = (self._rows(cols, source, k) for source in (truths[0], models[0]))
            if len(truth["t"]) < 2 or len(pred["t"]) == 0:
                raise PlotError(f"{path}: trajectory {k:g} lacks the {truths[0]} rows or the"
                                f" {models[0]} rows")
            if len(truth["t"]) != len(pred["t"]) or not np.allclose(truth["t"], pred["t"]):
                truth, moved = truth_at(truth, pred["t"]), moved + 1
            self.trajs.append({"t": truth["t"],
                               "true": np.stack([truth[n] for n in names], axis=1),
                               "pred": np.stack([pred[n] for n in names], axis=1),
                               "true_energy": truth["energy"],
                               "pred_energy": pred["energy"],
                               "learned_h": pred["learned_h"]})
        if moved:
            note(f"{path}: the truth of {moved} trajectories is sampled at other times than the"
                 " model's: drawn interpolated between its samples, and not past its end")

    @staticmethod
    def _rows(cols, source, traj):
        """The numeric columns of one source's rows of one trajectory, in time order."""
        rows = (cols["source"] == source) & (cols["traj"] == traj)
        order = np.argsort(cols["t"][rows], kind="stable")
        return {name: cols[name][rows][order] for name in cols if name != "source"}

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

    def valid_prediction_time(self, threshold=0.1):
        """The mean over trajectories of the time until the relative state error |x^ - x| /
        (|x^| + |x|) first passes `threshold` (the whole span when it never does), as hnn's
        valid_prediction_time (tasks/evaluate/state_errors.cpp); rows without a truth are
        skipped."""
        times = []
        for tr in self.trajs:
            gap = np.linalg.norm(tr["pred"] - tr["true"], axis=1)
            error = gap / (np.linalg.norm(tr["pred"], axis=1) + np.linalg.norm(tr["true"], axis=1))
            past = [k for k in range(1, len(tr["t"])) if np.all(np.isfinite(tr["true"][k]))
                    and not error[k] <= threshold]
            times.append(tr["t"][past[0] if past else -1] - tr["t"][0])
        return float(np.mean(times))

    def energy_mse(self):
        """The mean over trajectories of the mean over time of (E(x) - E(x^))^2, the true
        energy along the truth against along the model's path, as hnn's energy_mse; None
        without both."""
        per = []
        for tr in self.trajs:
            gap = (tr["true_energy"] - tr["pred_energy"]) ** 2
            if np.any(np.isfinite(gap)):
                per.append(np.nanmean(gap))
        return float(np.mean(per)) if per else None

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



def setting(metrics, key):
    """metrics.json's `key`, at its top level (where `hnn train` puts its settings) or in a
    "settings" object."""
    if key in metrics:
        return metrics[key]
    settings = metrics.get("settings")
    return settings.get(key) if isinstance(settings, dict) else None


def energy_summary(runs):
    """' (energy MSE: baseline 1.7e-01, HNN 3.8e-04)' from metrics.json (for a run marked
    "of_file", an `hnn rollout` file: of its own rollouts), or ''."""
    parts = []
    for model in MODELS:
        run = runs.get(model) or {}
        value = (run["rollout"].energy_mse() if run.get("of_file")
                 else (run.get("metrics") or {}).get("energy_mse"))
        if is_number(value):
            parts.append(f"{'HNN' if model == 'hnn' else model} {value:.2e}")
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


