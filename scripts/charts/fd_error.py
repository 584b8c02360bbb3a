"""Error of a gradient by finite differences against the step h, with autodiff's as a flat line
(fd_error), from fd_error.csv of bench/accuracy/fd_vs_autodiff."""

import os
from collections import defaultdict

import matplotlib.pyplot as plt

from .common import read_rows, save

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


def plot_fd_error(directory):
    rows = read_rows(os.path.join(directory, "fd_error.csv"))
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
    save(fig, directory, "fd_error", bbox_inches="tight")
