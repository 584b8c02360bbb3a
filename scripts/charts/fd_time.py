"""Time of a gradient against input dimension and parameter count, autodiff against finite
differences (fd_time), from fd_time_dim.csv and fd_time_params.csv of
bench/accuracy/fd_vs_autodiff."""

import os
from collections import defaultdict

import matplotlib.pyplot as plt

from .common import read_rows, save

TIME_STYLE = {
    "evaluation": dict(color="tab:green", marker="^", label="one evaluation"),
    "autodiff": dict(color="black", marker="D", label="autodiff (reverse mode)"),
    "forward": dict(color="tab:orange", marker="o", label="one-sided differences"),
    "central": dict(color="tab:blue", marker="s", label="central differences"),
}


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
    dim_rows = read_rows(os.path.join(directory, "fd_time_dim.csv"))
    param_rows = read_rows(os.path.join(directory, "fd_time_params.csv"))
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
    save(fig, directory, "fd_time", bbox_inches="tight")
