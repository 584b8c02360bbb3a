"""Runs: hnn.train, the hnn program's `hnn train` from Python, and run folders opened again.

A run folder is the same whoever wrote it: metrics.json, loss_curve.csv, params.bin and the
task's files (rollout.csv, ...). hnn.train writes one as `hnn train` does; hnn.load_run opens
any, including those the hnn program wrote."""

import csv
import json
import math
import os

import numpy as np

from . import _hnn

__all__ = ["Run", "train", "load_run"]


def train(task=None, model=None, seed=None, out=None, resume=False, **options):
    """Runs `hnn train TASK --model MODEL --seed SEED --out OUT --OPTION VALUE...` and returns
    the Run. Options are `hnn train`'s (its table: docs/inputs.md), with '_' for '-'
    (lr_schedule="cosine"), e.g. steps=200, hidden=[32, 32], dtype="float", settings={...};
    model and seed default to "hnn" and 0. Without `out`, the folder is hnn train's default,
    runs/TASK/MODEL. Ctrl-C stops after the current step with a checkpoint and raises
    KeyboardInterrupt.

    resume=True continues the run in `out`, resume=DIR the run in DIR, as `hnn train --resume
    DIR` does: an interrupted run to its end from its last checkpoint, a finished one to a
    larger `steps`. The run keeps its own settings: no task, and only the options that cannot
    change its result (threads, quiet, checkpoint_every, ...)."""
    folder = ""
    if resume is True:
        if out is None:
            raise _hnn.Error("train: resume=True continues the run in out: give out, or "
                             "resume=DIR")
        folder, out = os.fspath(out), None
    elif resume is not False and resume is not None:
        folder = os.fspath(resume)
    if not folder:
        if task is None:
            raise _hnn.Error("train needs a task (or resume=True with out, or resume=DIR)")
        model = "hnn" if model is None else model
        seed = 0 if seed is None else seed
    options.update(model=model, seed=seed, out=None if out is None else os.fspath(out))
    return Run(_hnn._train(task or "", json.dumps(options), folder))


def load_run(path):
    """The run in a folder written by hnn.train or by the hnn program."""
    return Run(path)


def _number(cell):
    return float(cell) if cell != "" else math.nan


def _stack(blocks):
    """One array when every block has the same length, else a list of arrays."""
    arrays = [np.array(b, dtype=float) for b in blocks]
    if len({a.shape for a in arrays}) == 1:
        return np.stack(arrays)
    return arrays


class Run:
    """A run folder: .metrics (metrics.json), .loss_curve and .rollouts (arrays), .model."""

    def __init__(self, path):
        self.path = os.fspath(path)
        metrics = os.path.join(self.path, "metrics.json")
        if not os.path.isfile(metrics):
            raise _hnn.Error(f"'{self.path}' is not a run folder: it has no metrics.json")
        with open(metrics) as f:
            self.metrics = json.load(f)
        self._model = None

    def __repr__(self):
        return f"<hnn.Run {self.path}>"

    @property
    def loss_curve(self):
        """loss_curve.csv by column: {"step": [...], "train_loss": [...], "test_loss": [...]}
        (the column names as the file has them); empty for a run without one (a sampled fit
        takes no steps)."""
        path = os.path.join(self.path, "loss_curve.csv")
        if not os.path.isfile(path):
            return {}
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        return {name: np.array([_number(r[i]) for r in rows[1:]])
                for i, name in enumerate(rows[0])}

    @property
    def rollouts(self):
        """rollout.csv by source ("true", the model's name, "data"): for each, "t" [traj, times],
        "x" [traj, times, dim], "energy" and "learned_h" [traj, times] (NaN where the file has
        no value); lists of arrays when trajectories differ in length. Empty when the run
        wrote no rollout.csv."""
        path = os.path.join(self.path, "rollout.csv")
        if not os.path.isfile(path):
            return {}
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        blocks = {}
        for row in rows[1:]:
            blocks.setdefault(row[0], {}).setdefault(row[1], []).append(
                [_number(c) for c in row[2:]])
        out = {}
        for source, trajectories in blocks.items():
            paths = list(trajectories.values())
            values = _stack(paths)
            if isinstance(values, list):
                out[source] = {"t": [p[:, 0] for p in values], "x": [p[:, 1:-2] for p in values],
                               "energy": [p[:, -2] for p in values],
                               "learned_h": [p[:, -1] for p in values]}
            else:
                out[source] = {"t": values[:, :, 0], "x": values[:, :, 1:-2],
                               "energy": values[:, :, -2], "learned_h": values[:, :, -1]}
        return out

    @property
    def state_names(self):
        """The state's column names, as rollout.csv has them ([] without one)."""
        path = os.path.join(self.path, "rollout.csv")
        if not os.path.isfile(path):
            return []
        with open(path, newline="") as f:
            return next(csv.reader(f))[3:-2]

    @property
    def model(self):
        """The trained model in the data's units, float64 (as `hnn export` gives it)."""
        if self._model is None:
            self._model = _hnn.Model.load(self.path)
        return self._model
