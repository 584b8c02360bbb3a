"""What every chart shares: matplotlib's backend and style, the error and note of a chart
command, the readers of JSON and CSV inputs, the paper's names and colours, and the atomic
PNG + SVG writer."""

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
# Charts 3 and 4 of docs/speed_accuracy.md (charts/float_double.py, charts/model_size.py).
SHORT_TITLES = {"spring": "Mass-spring", "pendulum": "Pendulum", "real-pendulum": "Real pendulum",
                "two-body": "Two-body", "three-body": "Three-body",
                "pixel-pendulum": "Pixel pendulum"}
SIZE_COLORS = {"hnn": "tab:blue", "baseline": "tab:orange"}
SIZE_LABELS = {"hnn": "HNN", "baseline": "baseline"}
PIXEL_TASK = "pixel-pendulum"  # rollouts of frames, drawn by charts/fig4_pixel.py
# The measurement charts (docs/speed_accuracy.md) draw a light grid; used as plt.rc_context.
GRID = {"axes.grid": True, "grid.alpha": 0.3}
UMASK = os.umask(0o022)
os.umask(UMASK)

plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "hnn", "font.size": 9,
                     "axes.titlesize": 10, "legend.fontsize": 8})


class PlotError(Exception):
    """An input exists but cannot be used; the message names the file."""


def program():
    """The command's name for its messages: plot.py, plot_pixel.py, ..."""
    return os.path.basename(sys.argv[0]) or "charts"


def note(message):
    print(f"{program()}: note: {message}", file=sys.stderr)


def error(message):
    """Prints the command's one-line error and returns its exit code, 1."""
    print(f"{program()}: error: {message}", file=sys.stderr)
    return 1


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# ---------------------------------------------------------------------------------------------
# Reading


def present(rows):
    """The tasks of TASKS that some row ({"task": ...}) is of, in the paper's order."""
    return [t for t in TASKS if any(r["task"] == t for r in rows)]


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise PlotError(f"{path}: not valid JSON: {e}") from e


def pixel_run(results, model):
    """RESULTS_DIR/pixel-pendulum/MODEL: the run folder of one pixel model."""
    return os.path.join(results, PIXEL_TASK, model)


def read_optional(path, reader):
    """reader(path), or None with a note when the file is missing."""
    if not os.path.isfile(path):
        note(f"{os.path.relpath(path)}: missing, skipped")
        return None
    return reader(path)


def to_float(cell, path, line, column):
    """A CSV cell as a float; an empty cell is NaN (e.g. learned_h of the baseline)."""
    cell = cell.strip()
    if cell == "":
        return math.nan
    try:
        return float(cell)
    except ValueError:
        raise PlotError(f"{path}:{line}: column '{column}': not a number: {cell!r}") from None


def read_csv(path, required, text=()):
    """Reads a CSV with a header into {column: np.ndarray}: numbers, but the columns named in
    `text` (such as a rollout CSV's "source") as strings. Checks the required columns and that
    every row has as many cells as the header."""
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
        values.append([c.strip() if h in text else to_float(c, path, line, h)
                       for c, h in zip(row, header)])
    if not values:
        raise PlotError(f"{path}: no data rows")
    return {h: np.array([v[i] for v in values], dtype=str if h in text else float)
            for i, h in enumerate(header)}


def read_loss_curve(path):
    """loss_curve.csv as {'step', 'train_loss', 'test_loss', 'units'}: a data run's columns
    are train_loss_standardised and test_loss_standardised (units "standardised"); files
    written before they said so have the plain names (units None)."""
    with open(path, newline="", encoding="utf-8", errors="replace") as f:
        header = f.readline()
    suffix = "_standardised" if "train_loss_standardised" in header else ""
    cols = read_csv(path, ["step", f"train_loss{suffix}", f"test_loss{suffix}"])
    return {"step": cols["step"], "train_loss": cols[f"train_loss{suffix}"],
            "test_loss": cols[f"test_loss{suffix}"], "units": suffix[1:] or None}


def read_rows(path):
    """A CSV with a header as a list of {column: text} (the benchmarks' and hnn sweep's)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# ---------------------------------------------------------------------------------------------
# Writing


def save(fig, folder, stem, **savefig_options):
    """Writes stem.png and stem.svg atomically (temp file in the same folder, then rename) and
    prints their paths. savefig_options go to matplotlib (e.g. bbox_inches="tight")."""
    written = []
    for ext in ("png", "svg"):
        final = os.path.join(folder, f"{stem}.{ext}")
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{stem}.", suffix=f".{ext}.tmp")
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
        # The layout is placed: the SVG keeps the PNG's, instead of solving the constrained layout
        # again (plot.py on the test fixture: 14% less time; the SVG moves by under a point).
        if fig.get_layout_engine() is not None:
            fig.set_layout_engine("none")
    plt.close(fig)
    return written


def write_text(path, text):
    """Writes a text file atomically (a temporary file beside it, then renamed)."""
    tmp = f"{path}.tmp"
    with open(tmp, "w", newline="") as f:
        f.write(text)
    os.replace(tmp, path)
    return path
