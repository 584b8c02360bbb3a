"""hnn sweep's outputs beside the runs: the table of every run (results.csv and results.json),
the charts the spec asks for, and the Slurm job array of `hnn sweep --emit slurm`.
Used by sweep_driver.py; needs no Dask (matplotlib for the charts only)."""

import csv
import json
import math
import os
import shlex
import textwrap
import time


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def run_state(out, name):
    """("done", metrics) for a complete metrics.json, ("failed", its one-line reason) for a run
    that failed for its own reasons, else ("pending", None)."""
    folder = os.path.join(out, "runs", name)
    metrics = read_json(os.path.join(folder, "metrics.json"))
    if isinstance(metrics, dict):
        return "done", metrics
    try:
        with open(os.path.join(folder, "sweep_failed.txt")) as f:
            return "failed", f.read().strip()
    except OSError:
        return "pending", None


def write_atomic(path, text):
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def cell(value):
    """A value as one CSV cell: widths as 200-200, other lists and objects as JSON."""
    if value is None:
        return ""
    if isinstance(value, list) and value and all(isinstance(v, int) for v in value):
        return "-".join(str(v) for v in value)
    if isinstance(value, (list, dict, bool)):
        return json.dumps(value, separators=(",", ":"))
    return str(value)


def table_metrics(metrics):
    """A run's metrics.json as table columns: its "fit" block (how a sampled fit went) flattened
    to fit_method, fit_sampler, fit_solve_seconds, ..., so that it stands apart from the spec's
    `fit` key (the fit asked for) and each of its figures is a column of its own."""
    flat = {k: v for k, v in metrics.items() if k != "fit"}
    fit = metrics.get("fit")
    if isinstance(fit, dict):
        flat.update({f"fit_{k}": v for k, v in fit.items()})
    elif fit is not None:
        flat["fit_report"] = fit
    return flat


def write_table(plan):
    """OUT/results.json and OUT/results.csv: one row per run of the plan, in its order, with the
    spec's values, the run's state and its metrics.json. Returns the JSON rows."""
    out = plan["out"]
    rows = []
    for r in plan["runs"]:
        status, found = run_state(out, r["name"])
        rows.append({"run": r["name"], "status": status,
                     "reason": found if status == "failed" else "",
                     "values": r["values"],
                     "metrics": found if status == "done" else None,
                     "sweep": read_json(os.path.join(out, "runs", r["name"], "sweep.json"))})
    counts = {s: sum(1 for row in rows if row["status"] == s)
              for s in ("done", "failed", "pending")}
    document = {"spec": plan["spec"], "out": out, "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "counts": counts, "keys": plan["keys"], "runs": rows}
    write_atomic(os.path.join(out, "results.json"), json.dumps(document, indent=1) + "\n")

    table = [table_metrics(row["metrics"] or {}) for row in rows]
    metric_keys = sorted({k for metrics in table for k in metrics} - set(plan["keys"]))
    header = ["run", "status", "reason", *plan["keys"], "run_host", "run_seconds",
              "run_resumed", *metric_keys]
    lines = []
    for row, metrics in zip(rows, table):
        sweep = row["sweep"] or {}
        lines.append([row["run"], row["status"], row["reason"],
                      *[cell(row["values"].get(k)) for k in plan["keys"]],
                      cell(sweep.get("host")), cell(sweep.get("seconds")),
                      cell(sweep.get("resumed")), *[cell(metrics.get(k)) for k in metric_keys]])
    path = os.path.join(out, "results.csv")
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(lines)
    os.replace(tmp, path)
    return rows


# ---- charts ---------------------------------------------------------------------------------

def ordered(values):
    seen = []
    for v in values:
        if v not in seen:
            seen.append(v)
    return seen


def mean_and_error(ys):
    m = sum(ys) / len(ys)
    if len(ys) < 2:
        return m, 0.0
    var = sum((y - m) ** 2 for y in ys) / (len(ys) - 1)
    return m, math.sqrt(var / len(ys))


def metric_points(points, x_metric, y, series, facet):
    """A chart of one metric against another (x_metric: train_seconds against an error, say):
    one point per setting, its runs (the seeds) pooled, with the standard error of both means,
    ordered by x and labelled by the keys that vary among the points."""
    groups = {}
    for r in points:
        if not isinstance(r["metrics"].get(x_metric), (int, float)):
            continue
        key = tuple(sorted((k, cell(v)) for k, v in r["values"].items()
                           if k not in ("seed", series, facet)))
        groups.setdefault(key, []).append(r)
    varying = {k for key in groups for k, v in key
               if len({dict(other).get(k) for other in groups}) > 1}
    out = []
    for key, runs in groups.items():
        mx, ex = mean_and_error([r["metrics"][x_metric] for r in runs])
        my, ey = mean_and_error([r["metrics"][y] for r in runs])
        label = ",".join(f"{v}" for k, v in key if k in varying)
        out.append((mx, my, ex, ey, label))
    return sorted(out)


def draw_metric_series(ax, points, chart, series_value):
    got = metric_points(points, chart["x_metric"], chart["y"], chart.get("series"),
                        chart.get("facet"))
    if not got:
        return
    xs, ys, exs, eys, labels = zip(*got)
    ax.errorbar(xs, ys, xerr=exs, yerr=eys, marker="o", capsize=3, label=series_value)
    for x, y, label in zip(xs, ys, labels):
        if label:
            ax.annotate(label, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)


def draw_chart(plan, rows, chart, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    x, y = chart.get("x") or chart["x_metric"], chart["y"]
    series, facet = chart.get("series"), chart.get("facet")
    where = {k: [cell(v) for v in allowed] for k, allowed in chart.get("where", {}).items()}
    rows = [r for r in rows if all(cell(r["values"].get(k)) in allowed
                                   for k, allowed in where.items())]
    done = [r for r in rows if r["status"] == "done"
            and isinstance(r["metrics"].get(y), (int, float))]
    every_x = ordered(cell(r["values"].get(x)) for r in rows)
    numeric = "x_metric" in chart or all(isinstance(r["values"].get(x), (int, float))
                                         for r in rows)
    facets = ordered(cell(r["values"].get(facet)) for r in done) if facet else [None]
    width = 4.6 * max(1, len(facets))
    title = title_lines(chart["title"], width) if chart.get("title") else []
    fig, axes = plt.subplots(1, max(1, len(facets)), figsize=(width, 3.6 + 0.2 * len(title)),
                             squeeze=False)
    for ax, fv in zip(axes[0], facets):
        mine = [r for r in done if fv is None or cell(r["values"].get(facet)) == fv]
        for sv in ordered(cell(r["values"].get(series)) for r in mine) if series else [None]:
            points = [r for r in mine if sv is None or cell(r["values"].get(series)) == sv]
            if "x_metric" in chart:
                draw_metric_series(ax, points, chart, sv)
                continue
            xs, ms, es = [], [], []
            for xv in every_x:
                ys = [r["metrics"][y] for r in points if cell(r["values"].get(x)) == xv]
                if ys:
                    m, e = mean_and_error(ys)
                    xs.append(float(xv) if numeric else every_x.index(xv))
                    ms.append(m)
                    es.append(e)
            ax.errorbar(xs, ms, yerr=es, marker="o", capsize=3, label=sv)
        if not numeric and "x_metric" not in chart:
            ax.set_xticks(range(len(every_x)), every_x, rotation=30)
        if chart.get("log_x"):
            ax.set_xscale("log")
        if chart.get("log_y"):
            ax.set_yscale("log")
        readable_log_ticks(ax)
        ax.set_xlabel(x)
        ax.set_ylabel(y)
        if fv is not None:
            ax.set_title(f"{facet} {fv}")
        if series:
            ax.legend(title=series, fontsize=8)
    if title:
        fig.suptitle("\n".join(title), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def readable_log_ticks(ax):
    """On a log axis of ax spanning under a decade, where matplotlib labels every minor tick and
    the labels run into each other: four or so evenly spaced ticks, labelled in three digits."""
    from matplotlib.ticker import FuncFormatter, MaxNLocator, NullFormatter
    for axis, get in ((ax.xaxis, ax.get_xlim), (ax.yaxis, ax.get_ylim)):
        lo, hi = get()
        if axis.get_scale() != "log" or not 0 < lo < hi or hi >= 10 * lo:
            continue
        axis.set_major_locator(MaxNLocator(nbins=4))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
        axis.set_minor_formatter(NullFormatter())


def title_lines(text, width_inches):
    """text wrapped to a figure width_inches wide, as lines, for a title at font size 10 (about 13
    characters an inch): a title wider than its figure is cut off at both ends."""
    return textwrap.wrap(text, max(20, int(13 * width_inches)))


def write_charts(plan, rows):
    """The spec's charts (its "charts" list: x or x_metric, y, series, facet, where, log_x, log_y,
    title, file; a metric is a column of results.csv) as PNG files in OUT: the mean of y over
    the runs that differ in other keys (seeds, say), with its standard error. Returns their
    paths."""
    paths = []
    rows = [{**r, "metrics": table_metrics(r["metrics"] or {})} for r in rows]
    for i, chart in enumerate(plan.get("charts", [])):
        path = os.path.join(plan["out"], chart.get("file", f"chart-{i + 1}.png"))
        try:
            draw_chart(plan, rows, chart, path)
        except ImportError:
            print("hnn sweep: charts need matplotlib (Debian: python3-matplotlib)", flush=True)
            return paths
        paths.append(path)
    return paths


# ---- Slurm ----------------------------------------------------------------------------------

SLURM_HEAD = """#!/bin/bash
# {count} runs of {spec} as a Slurm job array, written by
#   hnn sweep {spec} --out {out} --emit slurm
# Submit it (every path is absolute; the nodes must share {out}):
#   sbatch {script}
# then, when the array has ended, gather the table (and charts):
#   hnn sweep {spec} --out {out} --collect
# A task skips a finished run and resumes an interrupted one from its checkpoint, so submitting
# again (or a requeue after preemption) redoes nothing. Slurm caps arrays at MaxArraySize
# (1001 by default): submit a longer one in parts, `sbatch --array=1000-1999 {script}`; and
# `--array=0-{last}%50` runs at most 50 at once.
#SBATCH --job-name=hnn-sweep
#SBATCH --array=0-{last}
#SBATCH --cpus-per-task={threads}
#SBATCH --output={out}/slurm/%A_%a.log
#SBATCH --requeue
set -euo pipefail
hnn={hnn}
threads=${{SLURM_CPUS_PER_TASK:-{threads}}}

# train RUN_FOLDER ARGS...: hnn train ARGS --out RUN_FOLDER, unless finished or interrupted.
train() {{
  local run=$1
  shift
  if [ -s "$run/metrics.json" ]; then
    echo "hnn sweep: $run is finished"
    return 0
  fi
  if [ -f "$run/checkpoint/state.json" ]; then
    exec "$hnn" train --resume "$run" --threads "$threads" --quiet
  fi
  exec "$hnn" train "$@" --threads "$threads" --quiet --out "$run"
}}

case "${{SLURM_ARRAY_TASK_ID:?submit with sbatch, or set SLURM_ARRAY_TASK_ID}}" in
"""


def write_slurm(plan):
    """OUT/sweep.slurm: one array task per run of the plan, in its order."""
    out = plan["out"]
    script = os.path.join(out, "sweep.slurm")
    os.makedirs(os.path.join(out, "slurm"), exist_ok=True)
    q = shlex.quote
    text = SLURM_HEAD.format(count=len(plan["runs"]), spec=q(plan["spec"]), out=q(out),
                             script=q(script), last=len(plan["runs"]) - 1, hnn=q(plan["hnn"]),
                             threads=plan["options"]["threads_per_run"])
    for i, r in enumerate(plan["runs"]):
        folder = os.path.join(out, "runs", r["name"])
        text += f"  {i}) train {q(folder)} {' '.join(q(a) for a in r['args'])} ;;\n"
    text += ('  *) echo "hnn sweep: no run $SLURM_ARRAY_TASK_ID (0-'
             f'{len(plan["runs"]) - 1})" >&2; exit 1 ;;\nesac\n')
    write_atomic(script, text)
    os.chmod(script, 0o755)
    return script
