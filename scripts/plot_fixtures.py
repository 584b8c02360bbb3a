"""Synthetic results for the chart tests (scripts/plot_test.py, plot_pixel_test.py,
plot_study_test.py): a results folder as `hnn reproduce` writes it, with a spring (exact circles
for the truth, a slowly spiralling baseline, an HNN close to the truth), a two-body circular
orbit and a three-body rotating triangle whose baseline diverges to inf/nan; run folders of the
data task; and the helpers that run a chart command and read a PNG's size.
"""

import json
import os
import struct
import subprocess

import numpy as np

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
PLOT = os.path.join(SCRIPTS, "plot.py")
PYTHON = "/usr/bin/python3"
KEYS = ["train_loss", "test_loss", "energy_mse"]
MODELS = ["baseline", "hnn"]


def write_rollout(path, t, trajs, model, truth="true", names=None):
    """rollout.csv as hnn writes it (tasks/report/rollout_csv.h): per trajectory the rows of the
    truth (source `truth`) and of `model`. trajs: list of (true states T x d, pred states T x d,
    true E, pred E, learned H), any of the last three None for empty cells; t: the times, shared
    or a list with one per trajectory; names: the state's columns (default x_0..x_{d-1})."""
    d = trajs[0][0].shape[1]
    names = names or [f"x_{i}" for i in range(d)]
    with open(path, "w") as f:
        f.write(",".join(["source", "traj", "t"] + names + ["energy", "learned_h"]) + "\n")
        for k, (true, pred, e_true, e_pred, h) in enumerate(trajs):
            times = t[k] if isinstance(t, list) else t
            for source, states, energy, learned in ((truth, true, e_true, None),
                                                     (model, pred, e_pred, h)):
                for i, ti in enumerate(times):
                    cells = [source, str(k), f"{ti:.6g}"] + [f"{v:.9g}" for v in states[i]]
                    cells += ["" if e is None else f"{e[i]:.9g}" for e in (energy, learned)]
                    f.write(",".join(cells) + "\n")


def write_paths(path, t, trajs, names, model, truth_rows=None):
    """The older layout of `hnn rollout`: source,traj,t,<names>,energy,learned_h, the truth's
    rows ("true") then the model's, of write_rollout's trajs; truth_rows: the truth's first rows
    only (a measured stretch that ends before the rollout)."""
    with open(path, "w") as f:
        f.write(",".join(["source", "traj", "t", *names, "energy", "learned_h"]) + "\n")
        for side in ("true", model):
            for k, (true, pred, e_true, e_pred, h) in enumerate(trajs):
                states, energy = (true, e_true) if side == "true" else (pred, e_pred)
                rows = truth_rows if side == "true" and truth_rows else len(t)
                for i, ti in enumerate(t[:rows]):
                    cells = [side, str(k), f"{ti:.6g}"] + [f"{v:.9g}" for v in states[i]]
                    cells.append("" if energy is None else f"{energy[i]:.9g}")
                    cells.append("" if h is None or side == "true" else f"{h[i]:.9g}")
                    f.write(",".join(cells) + "\n")


def write_loss_curve(path, final_train, final_test, steps):
    step = np.arange(0, steps + 1, steps // 40)
    decay = np.exp(-step / (steps / 6))
    with open(path, "w") as f:
        f.write("step,train_loss,test_loss\n")
        for s, g in zip(step, decay):
            f.write(f"{s},{final_train * (1 + 50 * g):.6g},{final_test * (1 + 40 * g):.6g}\n")


def write_model(root, task, model, metrics, steps, rollout):
    folder = os.path.join(root, task, model)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "metrics.json"), "w") as f:
        json.dump(dict(task=task, model=model, seed=0, steps=steps, dtype="float64",
                       n_rollouts=3, train_seconds=1.0, **metrics), f)
    write_loss_curve(os.path.join(folder, "loss_curve.csv"), metrics["train_loss"],
                     metrics["test_loss"], steps)
    write_rollout(os.path.join(folder, "rollout.csv"), *rollout, model)


def spring_rollouts(model):
    """H = q^2 + p^2: circles q = r cos(2t + a), p = -r sin(2t + a), energy r^2."""
    t = np.linspace(0, 20, 100)
    trajs = []
    for r, a in ((0.8, 0.3), (0.5, 1.0), (0.3, 2.0)):
        true = np.stack([r * np.cos(2 * t + a), -r * np.sin(2 * t + a)], axis=1)
        if model == "baseline":  # slowly spiralling inwards
            rr, phase = r * np.exp(-0.03 * t), 2 * t + a
        else:  # close to the truth: a small phase drift and a tiny radius wobble
            rr, phase = r * (1 + 0.01 * np.sin(t)), 2.01 * t + a
        pred = np.stack([rr * np.cos(phase), -rr * np.sin(phase)], axis=1)
        h = None if model == "baseline" else 0.7 * rr ** 2 + 0.1  # learned H: any offset/scale
        trajs.append((true, pred, np.sum(true ** 2, 1), np.sum(pred ** 2, 1), h))
    return t, trajs


def two_body_state(radius, angle):
    """Circular orbit of two unit masses at +-pos: (qx1, qx2, qy1, qy2, px1, px2, py1, py2)."""
    x, y = radius * np.cos(angle), radius * np.sin(angle)
    v = 0.5 / np.sqrt(radius)
    vx, vy = -v * np.sin(angle), v * np.cos(angle)
    return np.stack([x, -x, y, -y, vx, -vx, vy, -vy], axis=1)


def two_body_energy(s):
    dist = np.hypot(s[:, 0] - s[:, 1], s[:, 2] - s[:, 3])
    return 0.5 * np.sum(s[:, 4:] ** 2, axis=1) - 1 / dist


def two_body_rollouts(model):
    t = np.linspace(0, 20, 1000)
    trajs = []
    for radius, a in ((1.0, 0.2), (1.2, 1.5)):
        omega = 0.5 / radius ** 1.5
        true = two_body_state(np.full_like(t, radius), omega * t + a)
        if model == "baseline":  # drifts outwards
            pred = two_body_state(radius * (1 + 0.02 * t), omega * t * 0.97 + a)
        else:
            pred = two_body_state(radius * (1 + 2e-4 * t), omega * t * 1.003 + a)
        h = None if model == "baseline" else two_body_energy(pred) + 0.5
        trajs.append((true, pred, two_body_energy(true), two_body_energy(pred), h))
    return t, trajs


def three_body_state(radius, angle):
    """Equal masses on a rotating equilateral triangle: (qx1..3, qy1..3, px1..3, py1..3)."""
    offsets = np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3])
    a = angle[:, None] + offsets
    r = radius[:, None]
    speed = r * np.sqrt(1 / (np.sqrt(3) * r ** 3))
    return np.concatenate([r * np.cos(a), r * np.sin(a), -speed * np.sin(a),
                           speed * np.cos(a)], axis=1)


def three_body_energy(s):
    q = np.stack([s[:, 0:3], s[:, 3:6]], axis=2)  # T x body x (x, y)
    potential = sum(-1 / np.linalg.norm(q[:, i] - q[:, j], axis=1)
                    for i, j in ((0, 1), (0, 2), (1, 2)))
    return 0.5 * np.sum(s[:, 6:] ** 2, axis=1) + potential


def three_body_rollouts(model):
    """The baseline blows up: its last states are inf and nan, as a diverging run may write."""
    t = np.linspace(0, 5, 100)
    trajs = []
    for radius, a in ((1.0, 0.1), (1.1, 0.7)):
        omega = np.sqrt(1 / (np.sqrt(3) * radius ** 3))
        true = three_body_state(np.full_like(t, radius), omega * t + a)
        if model == "baseline":
            pred = three_body_state(radius * np.exp(0.25 * t ** 1.5), omega * t + a)
            pred[-5:-2], pred[-2:] = np.inf, np.nan
        else:
            pred = three_body_state(radius * (1 + 0.002 * t), omega * t * 1.01 + a)
        h = None if model == "baseline" else three_body_energy(pred) - 1.0
        trajs.append((true, pred, three_body_energy(true), three_body_energy(pred), h))
    return t, trajs


def data_rollouts(model, steps=(0.05, 0.05, 0.05)):
    """Two uncoupled oscillators, x = (x, y, p_x, p_y), measured in three held-out stretches of
    different lengths that start at different times, each sampled every steps[k]; no known H
    (empty energy cells). The baseline's amplitude decays, the HNN has a small phase error."""
    omega, amp = np.array([1.0, 1.7]), np.array([1.0, 0.6])
    times, trajs = [], []
    for k, (start, count) in enumerate(((3.0, 80), (12.5, 50), (30.0, 120))):
        t = start + steps[k] * np.arange(count)
        tau = t - t[0]

        def state(a, w, phase):
            return np.concatenate([a * np.cos(phase), -a * w * np.sin(phase)], axis=1)

        phase = omega * t[:, None] + 0.4 * k
        true = state(amp, omega, phase)
        if model == "baseline":
            pred = state(amp * np.exp(-0.05 * tau)[:, None], omega, phase + 0.02 * tau[:, None])
            h = None
        else:
            pred = state(amp, omega, phase + 0.004 * tau[:, None])
            h = 0.5 * np.sum(pred[:, 2:] ** 2 + (omega * pred[:, :2]) ** 2, axis=1) - 3.0
            h = h * (1 + 1e-3 * np.sin(tau))
        times.append(t)
        trajs.append((true, pred, None, None, h))
    return times, trajs


def write_data_run(folder, model, **rollout_options):
    """A run folder of `hnn train data` as the --runs mode reads it."""
    os.makedirs(folder, exist_ok=True)
    metrics = dict(task="data", model=model, seed=0, data_file="measured/oscillators.csv",
                   state_names=["x", "y", "p_x", "p_y"], energy_mse=None,
                   energy_note="no known Hamiltonian: give one with --hamiltonian EXPR",
                   valid_prediction_time=1.5 if model == "baseline" else 4.25,
                   coordinate_mse=2.1e-2 if model == "baseline" else 3.4e-4)
    if model == "hnn":  # the learned H's spread on the training states: 2.5e-3 / 1e-3
        metrics.update(learned_h_drift=2.5e-3, learned_h_drift_relative=1e-3)
    with open(os.path.join(folder, "metrics.json"), "w") as f:
        json.dump(metrics, f)
    write_rollout(os.path.join(folder, "rollout.csv"), *data_rollouts(model, **rollout_options),
                  model, truth="data", names=metrics["state_names"])
    return folder


ROLLOUTS = {"spring": spring_rollouts, "two-body": two_body_rollouts,
            "three-body": three_body_rollouts}
PAPER = {("spring", "baseline"): (3.7134e-2, 3.6656e-2, 1.7077e-1),
         ("spring", "hnn"): (3.6933e-2, 3.5928e-2, 3.8416e-4),
         ("two-body", "baseline"): (3.2682e-5, 2.9575e-5, 6.3276e-2),
         ("two-body", "hnn"): (2.9959e-6, 2.8218e-6, 3.8751e-5),
         ("three-body", "baseline"): (9.5573e-2, 3.8000e-1, 1.0906e+2),
         ("three-body", "hnn"): (8.0346e-2, 4.8809e-1, 4.1926e-2)}
OURS = {("spring", "baseline"): (3.9e-2, 3.8e-2, 1.2e-1),
        ("spring", "hnn"): (3.8e-2, 3.7e-2, 6.0e-4),
        ("two-body", "baseline"): (4.1e-5, 3.9e-5, 2.2e-2),
        ("two-body", "hnn"): (3.5e-6, 3.3e-6, 5.1e-5),
        ("three-body", "baseline"): (1.1e-1, 4.0e-1, 8.0e+1),
        ("three-body", "hnn"): (9.0e-2, 3.0e-1, 2.0e-2)}


def build_results(root):
    table = []
    for (task, model), values in OURS.items():
        metrics = {}
        for key, v in zip(KEYS, values):
            metrics[key], metrics[key + "_se"] = v, 0.05 * v
        steps = 2000 if task == "spring" else 10000
        write_model(root, task, model, metrics, steps, ROLLOUTS[task](model))
        paper = {"paper_" + k: v for k, v in zip(KEYS, PAPER[(task, model)])}
        table.append(dict(task=task, model=model, seed=0, steps=steps, dtype="float64",
                          n_rollouts=3, train_seconds=1.0, **metrics, **paper))
    with open(os.path.join(root, "table1.json"), "w") as f:
        json.dump(table, f, indent=1)


def run_plot(*args, script=PLOT, env=None):
    """Runs a chart script; env: variables added to this process's environment."""
    return subprocess.run([PYTHON, script, *args], capture_output=True, text=True, timeout=300,
                          env=None if env is None else {**os.environ, **env})


def png_size(path):
    """(width, height) from the IHDR chunk; raises if the file is not a PNG."""
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise AssertionError(f"{path}: not a PNG")
    return struct.unpack(">II", head[16:24])
