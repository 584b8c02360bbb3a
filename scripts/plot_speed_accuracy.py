#!/usr/bin/python3
"""Draws the speed-against-accuracy charts from the CSV files of bench/accuracy/ (matplotlib, Agg).

Usage: /usr/bin/python3 scripts/plot_speed_accuracy.py DIR

Reads from DIR (as written by fd_vs_autodiff and work_precision, see scripts/charts.sh):
  fd_error.csv, fd_time_dim.csv, fd_time_params.csv, work_precision.csv, energy_drift.csv
and writes into DIR, each as PNG and SVG:
  fd_error         error of finite differences against the step h, autodiff's as a flat line
  fd_time          time of a gradient against input dimension and against parameter count
  work_precision   integrators: error at t = 10 against wall time and field evaluations
  energy_drift     relative energy error over long horizons, true systems and a trained HNN
A missing CSV skips its chart with a note on stderr. Each written file's path goes to stdout.
"""

import csv
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot  # noqa: E402  (the atomic PNG+SVG writer)

plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "hnn", "font.size": 9,
                     "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 8})

FD_STYLE = {
    "forward": dict(color="tab:orange", marker="o", ms=3, label="one-sided (forward) differences"),
    "central": dict(color="tab:blue", marker="s", ms=3, label="central differences"),
    "autodiff_double": dict(color="black", lw=2, label="autodiff, float64"),
    "autodiff_float": dict(color="gray", lw=1.5, ls="--", label="autodiff, float32"),
}
FD_CASES = {
    "pendulum_H": "Pendulum: dH/dx, H = 3(1 - cos q) + p²",
    "two_body_H": "Two-body: dH/dx (8 coordinates)",
    "hnn_H": "Trained 2-200-200-1 HNN: dH/dx",
    "hnn_loss_params": "HNN loss: gradient w.r.t. parameters\n(2-200-200-1, spring data, 750 states)",
}
TIME_STYLE = {
    "evaluation": dict(color="tab:green", marker="^", label="one evaluation"),
    "autodiff": dict(color="black", marker="D", label="autodiff (reverse mode)"),
    "forward": dict(color="tab:orange", marker="o", label="one-sided differences"),
    "central": dict(color="tab:blue", marker="s", label="central differences"),
}
METHOD_STYLE = {
    "euler": dict(color="tab:red", marker="v", label="Euler (dt sweep)"),
    "rk4": dict(color="tab:orange", marker="o", label="RK4 (dt sweep)"),
    "dopri5": dict(color="black", marker="*", label="DOPRI5 (rtol sweep)"),
    "leapfrog": dict(color="tab:green", marker="s", label="leapfrog (dt sweep)"),
    "yoshida4": dict(color="tab:blue", marker="D", label="Yoshida-4 (dt sweep)"),
    "midpoint": dict(color="tab:purple", marker="^", label="implicit midpoint (dt sweep)"),
}
SYSTEMS = {"spring": "Mass-spring", "pendulum": "Pendulum", "two_body": "Two-body",
           "2body": "Two-body", "hnn_spring": "Trained HNN (spring, 2-64-64-1)"}


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save(fig, directory, name):
    plot.save(fig, directory, name, bbox_inches="tight")


def plot_fd_error(directory):
    rows = read_csv(os.path.join(directory, "fd_error.csv"))
    series = defaultdict(list)
    for r in rows:
        series[(r["case"], r["method"])].append((float(r["h"]), float(r["error"])))
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), sharex=True)
    for ax, (case, title) in zip(axes.flat, FD_CASES.items()):
        for method, style in FD_STYLE.items():
            points = sorted(series.get((case, method), []))
            if not points:
                continue
            h, err = zip(*points)
            err = [max(e, 1e-18) for e in err]  # an exact zero would vanish on a log axis
            if method.startswith("autodiff"):
                ax.plot(h, err, **style)
            else:
                ax.plot(h, err, **style, lw=1.2)
                best = min(range(len(err)), key=err.__getitem__)
                ax.annotate(f"{err[best]:.0e} at h={h[best]:.0e}", (h[best], err[best]),
                            textcoords="offset points", xytext=(0, -14), ha="center",
                            fontsize=7, color=style["color"])
        ax.set(xscale="log", yscale="log", title=title, ylim=(1e-18, 1))
        ax.invert_xaxis()
    for ax in axes[1]:
        ax.set_xlabel("finite-difference step h (decreasing →)")
    for ax in axes[:, 0]:
        ax.set_ylabel("relative error  max|g − g_ref| / max|g_ref|")
    axes[0, 0].legend(loc="lower left")
    fig.suptitle("Gradient error: finite differences vs autodiff (reference: long-double "
                 "analytic gradient, or hand-derived MLP backprop for the HNN)", fontsize=10)
    fig.tight_layout()
    save(fig, directory, "fd_error")


def time_series(rows, key):
    series = defaultdict(list)
    for r in rows:
        series[r["method"]].append((float(r[key]), float(r["seconds"]), float(r["seconds_min"]),
                                    float(r["seconds_max"]), float(r["evaluations"])))
    return {m: sorted(v) for m, v in series.items()}


def plot_time_panel(ax_time, ax_ratio, series, xlabel):
    evaluation = {x: t for x, t, _, _, _ in series.get("evaluation", [])}
    evaluations = {m: [e for _, _, _, _, e in v] for m, v in series.items()}
    for method, style in TIME_STYLE.items():
        points = series.get(method, [])
        if not points:
            continue
        x, t, lo, hi, _ = zip(*points)
        ax_time.errorbar(x, [v * 1e3 for v in t],
                         yerr=[[(a - b) * 1e3 for a, b in zip(t, lo)],
                               [(b - a) * 1e3 for a, b in zip(t, hi)]],
                         capsize=2, lw=1.2, ms=4, **style)
        if method in ("forward", "central"):  # what the ratio would be at 1 evaluation each
            ax_ratio.plot(x, evaluations[method], color=style["color"], ls=":", lw=1)
        ratio = [(xi, ti / evaluation[xi]) for xi, ti in zip(x, t) if xi in evaluation]
        if ratio:
            ax_ratio.plot(*zip(*ratio), lw=1.2, ms=4, **style)
            xi, r = ratio[-1]
            ax_ratio.annotate(f"{r:.3g}×", (xi, r), textcoords="offset points", xytext=(4, 2),
                              fontsize=7, color=style["color"])
    ax_time.set(xscale="log", yscale="log", ylabel="time per gradient (ms, median)")
    ax_ratio.set(xscale="log", yscale="log", xlabel=xlabel,
                 ylabel="time / time of one evaluation\n(dotted: number of evaluations FD needs)")


def plot_fd_time(directory):
    dim_rows = read_csv(os.path.join(directory, "fd_time_dim.csv"))
    param_rows = read_csv(os.path.join(directory, "fd_time_params.csv"))
    dim = time_series(dim_rows, "dim")
    params = time_series(param_rows, "params")
    threads = sorted({r.get("threads", "?") for r in dim_rows + param_rows})
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    plot_time_panel(axes[0, 0], axes[1, 0], dim, "input dimension d (spring 2, two-body 8, "
                    "three-body 12, pixels 1568)")
    axes[0, 0].set_title("dH/dx of a d-200-200-1 tanh HNN on 32 states")
    plot_time_panel(axes[0, 1], axes[1, 1], params, "parameter count of a 2-w-w-1 HNN "
                    "(w = 4 ... 200)")
    axes[0, 1].set_title("HNN loss gradient w.r.t. all parameters (spring, 750 states)")
    for ax in axes[:, 0]:
        ax.set_xticks([2, 8, 12, 1568], ["2", "8", "12", "1568"])
    fd_params = [x for x, *_ in params.get("forward", [])]
    all_params = [x for x, *_ in params.get("evaluation", [])]
    if fd_params and max(fd_params) < max(all_params):
        axes[0, 1].text(0.97, 0.03, f"finite differences timed up to {max(fd_params):.0f} "
                        "parameters;\nbeyond, one gradient would take minutes",
                        transform=axes[0, 1].transAxes, ha="right", va="bottom", fontsize=7.5)
    axes[0, 0].legend(loc="upper left")
    fig.suptitle("Cost of a gradient: autodiff vs finite differences (float64, "
                 f"{'/'.join(threads)} engine thread(s); median of interleaved repetitions, "
                 "error bars min-max)", fontsize=10)
    fig.tight_layout()
    save(fig, directory, "fd_time")


def plot_work_precision(directory):
    rows = read_csv(os.path.join(directory, "work_precision.csv"))
    systems = [s for s in ("spring", "pendulum", "two_body") if any(r["system"] == s for r in rows)]
    fig, axes = plt.subplots(2, len(systems), figsize=(4.2 * len(systems), 7.5), squeeze=False)
    for col, system in enumerate(systems):
        for method, style in METHOD_STYLE.items():
            # In sweep order (largest dt or rtol first), so timing noise cannot reorder the line.
            points = sorted(((-float(r["value"]), float(r["seconds"]), float(r["nfev"]),
                              float(r["error"]))
                             for r in rows if r["system"] == system and r["method"] == method))
            if not points:
                continue
            _, seconds, nfev, error = zip(*points)
            axes[0, col].plot(seconds, error, lw=1.2, ms=4, **style)
            axes[1, col].plot(nfev, error, lw=1.2, ms=4, **style)
        reference = "exact solution" if system == "spring" else "DOPRI5 at rtol 1e-13"
        axes[0, col].set_title(f"{SYSTEMS[system]} (16 states to t = 10; reference: {reference})",
                               fontsize=8.5)
        axes[0, col].set(xscale="log", yscale="log", xlabel="wall time (s, median)")
        axes[1, col].set(xscale="log", yscale="log", xlabel="field evaluations (batched)")
    for ax in axes[:, 0]:
        ax.set_ylabel("max |x(10) − x_ref(10)| over states")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=6, bbox_to_anchor=(0.5, -0.03))
    fig.suptitle("Work-precision of the integrators: dt from 0.1 to 1e-4, rtol from 1e-3 to 1e-12",
                 fontsize=10)
    fig.tight_layout()
    save(fig, directory, "work_precision")


def plot_energy_drift(directory):
    rows = read_csv(os.path.join(directory, "energy_drift.csv"))
    systems = [s for s in ("spring", "pendulum", "2body", "hnn_spring")
               if any(r["system"] == s for r in rows)]
    fig, axes = plt.subplots(2, 2, figsize=(10, 8), sharey=True)
    for ax, system in zip(axes.flat, systems):
        learned = system == "hnn_spring"
        for method, style in METHOD_STYLE.items():
            for quantity in ("learned_H", "true_H"):
                points = sorted((float(r["periods"]), float(r["error"])) for r in rows
                                if r["system"] == system and r["method"] == method
                                and r["quantity"] == quantity)
                if not points:
                    continue
                name = style["label"].split(" (")[0]
                if learned:
                    name += ": learned H" if quantity == "learned_H" else ": true spring H"
                ls = ":" if learned and quantity == "true_H" else "-"
                ax.plot(*zip(*points), color=style["color"], ls=ls, lw=1.3, label=name)
        title = SYSTEMS.get(system, system)
        if learned:
            title += "\nnon-separable H (no leapfrog/Yoshida); periods of the true spring"
            ax.legend(loc="lower right", fontsize=7)
        ax.set(xscale="log", yscale="log", ylim=(1e-16, 10), title=title)
    for ax in axes[1]:
        ax.set_xlabel("simulated time (periods)")
    for ax in axes[:, 0]:
        ax.set_ylabel("max relative energy error |E(t) − E(0)| / |E(0)|\n"
                      "in log-spaced time bins (20 per decade)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=6, bbox_to_anchor=(0.5, -0.03))
    fig.suptitle("Long-horizon energy error: 32 fixed steps per period (64 for two-body), DOPRI5 "
                 "at rtol 1e-8;\nEuler stops where its error exceeds 10", fontsize=10)
    fig.tight_layout()
    save(fig, directory, "energy_drift")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    directory = sys.argv[1]
    charts = [("fd_error.csv", plot_fd_error), ("fd_time_dim.csv", plot_fd_time),
              ("work_precision.csv", plot_work_precision), ("energy_drift.csv", plot_energy_drift)]
    for name, plot in charts:
        if not os.path.exists(os.path.join(directory, name)):
            print(f"plot_speed_accuracy: {name} missing, chart skipped", file=sys.stderr)
            continue
        plot(directory)


if __name__ == "__main__":
    main()
