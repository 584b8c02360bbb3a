"""hnn sweep's table of runs (SWEEP_DIR/results.csv, see docs/sweeps.md) as the studies read it,
and the mean and standard error over seeds that their tables print."""

import json
import math
import os

from .common import PlotError, note, read_rows

# The state's dimension of each task: the input width of its network (the pixel pendulum's
# latent HNN, its autoencoder aside), for the parameter count of a hidden-layer shape.
STATE_DIM = {"spring": 2, "pendulum": 2, "real-pendulum": 2, "two-body": 8, "three-body": 12,
             "pixel-pendulum": 2}


def param_count(task, model, widths):
    """Weights and biases of the MLP: dim -> widths... -> 1 (HNN's H) or dim (baseline's
    field)."""
    dim = STATE_DIM[task]
    sizes = [dim] + list(widths) + [1 if model == "hnn" else dim]
    return sum((a + 1) * b for a, b in zip(sizes, sizes[1:]))


def read_results(folder, required=("task", "model")):
    """The runs of SWEEP_DIR/results.csv, each a {column: text}: its status (done, failed,
    pending) and reason, the spec's keys (hidden as 200-200, settings as JSON) and every key of
    the run's metrics.json. A run not done gets a note; a missing table or column is an
    error. finished() keeps the runs that are done."""
    path = os.path.join(folder, "results.csv")
    if not os.path.isfile(path):
        raise PlotError(f"{path}: missing (run `hnn sweep SPEC --out {folder}` first)")
    rows = read_rows(path)
    header = set(rows[0]) if rows else set()
    missing = [c for c in ("status", *required) if c not in header]
    if missing:
        raise PlotError(f"{path}: no column(s) {', '.join(missing)}")
    for r in rows:
        if r["status"] != "done":
            note(f"{r['run']}: {r['status']}{': ' + r['reason'] if r['reason'] else ''}")
    return rows


def finished(rows):
    return [r for r in rows if r["status"] == "done"]


def with_sizes(rows, path):
    """Adds depth, width and params (as text, like the other cells) from each run's hidden
    widths; a run without them is an error (the spec must give `hidden`)."""
    for r in rows:
        try:
            widths = [int(w) for w in r.get("hidden", "").split("-")]
        except ValueError:
            raise PlotError(f"{path}: run {r['run']}: hidden {r.get('hidden')!r} is not widths"
                            " such as 200-200 (give `hidden` in the spec)") from None
        r.update(depth=str(len(widths)), width=str(max(widths)),
                 params=str(param_count(r["task"], r["model"], widths)))
    return rows


def num(r, key):
    """A cell as a float; empty or absent is NaN."""
    v = r.get(key, "")
    return float(v) if v not in ("", None) else math.nan


def value(r, key):
    """A metric cell as a number, or None when empty (a metric the run does not have)."""
    v = r.get(key, "")
    return None if v in ("", None) else float(v)


def settings(r):
    """The run's task settings (the spec's `settings`, a JSON object), {} without them."""
    text = r.get("settings", "")
    return json.loads(text) if text else {}


def mean_se(values):
    """(mean, standard error of the mean, n) over the finite values; NaN where undefined (no
    values; one value has no standard error)."""
    values = [v for v in values if v is not None and math.isfinite(v)]
    if not values:
        return math.nan, math.nan, 0
    mean = sum(values) / len(values)
    if len(values) < 2:
        return mean, math.nan, 1
    var = sum((v - mean) ** 2 for v in values) / (len(values) - 1)
    return mean, math.sqrt(var / len(values)), len(values)


def cell(values, digits=3):
    """'mean ± se' over seeds ('mean' for one seed), as the results tables print it."""
    mean, se, _ = mean_se(values)
    return f"{mean:.{digits}g} ± {se:.1g}" if math.isfinite(se) else f"{mean:.{digits}g}"
