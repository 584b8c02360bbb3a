"""Work-precision of the integrators: error at t = 10 against wall time and field evaluations
(work_precision), from work_precision.csv of bench/accuracy/work_precision."""

import os

import matplotlib.pyplot as plt

from .common import read_rows, save

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



def plot_work_precision(directory):
    rows = read_rows(os.path.join(directory, "work_precision.csv"))
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
    save(fig, directory, "work_precision", bbox_inches="tight")
