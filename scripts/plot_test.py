#!/usr/bin/python3
"""Tests the charts package (scripts/charts/) through its commands. scripts/plot.py on a synthetic
results folder: a spring (exact circles for the truth, a slowly spiralling baseline, an HNN close
to the truth), a two-body circular orbit, and a three-body rotating triangle whose baseline
diverges to inf/nan; scripts/plot_pixel.py on synthetic pixel files; scripts/plot_study.py on
synthetic tables of hnn sweep (results.csv): the lean choice and the results tables.

Usage: /usr/bin/python3 scripts/plot_test.py [-v]      (KEEP=DIR keeps the folder in DIR)
"""

import csv
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

import numpy as np

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, SCRIPTS)
from charts import lean, sweep_table  # noqa: E402  (the package beside this file)

PLOT = os.path.join(SCRIPTS, "plot.py")
PYTHON = "/usr/bin/python3"
KEYS = ["train_loss", "test_loss", "energy_mse"]
MODELS = ["baseline", "hnn"]


# ---------------------------------------------------------------------------------------------
# Synthetic results


def write_rollout(path, t, trajs):
    """trajs: list of (true states T x d, pred states T x d, true E, pred E, learned H), any of
    the last three None for empty cells; t: the times, shared or a list with one per trajectory."""
    d = trajs[0][0].shape[1]
    header = (["traj", "t"] + [f"true_{i}" for i in range(d)] + [f"pred_{i}" for i in range(d)]
              + ["true_energy", "pred_energy", "learned_h"])
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for k, (true, pred, e_true, e_pred, h) in enumerate(trajs):
            for i, ti in enumerate(t[k] if isinstance(t, list) else t):
                cells = [str(k), f"{ti:.6g}"] + [f"{v:.9g}" for v in true[i]]
                cells += [f"{v:.9g}" for v in pred[i]]
                cells += ["" if e is None else f"{e[i]:.9g}" for e in (e_true, e_pred, h)]
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
    write_rollout(os.path.join(folder, "rollout.csv"), *rollout)


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
    write_rollout(os.path.join(folder, "rollout.csv"), *data_rollouts(model, **rollout_options))
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


# ---------------------------------------------------------------------------------------------
# Tests


def run_plot(*args, script=PLOT):
    return subprocess.run([PYTHON, script, *args], capture_output=True, text=True, timeout=300)


def write_pixel_results(root):
    """The files `hnn reproduce`, `hnn bump` and `hnn reversibility --report` write for the pixel
    pendulum: rollouts of decoded frames, the latent grid and paths, the bump, the strip."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for m in MODELS:
        folder = os.path.join(root, "pixel-pendulum", m)
        os.makedirs(folder, exist_ok=True)
        drift = 0.01 if m == "baseline" else 0.001
        with open(os.path.join(folder, "pixel_rollout.csv"), "w") as f:
            f.write("traj,frame,frame_mse,true_energy,pred_energy,pred_theta,true_theta\n")
            for k in range(3):
                for i in range(40):
                    f.write(f"{k},{i},{1e-3 * (1 + drift * 10 * i):.6g},{1 + 0.1 * k:.6g},"
                            f"{1 + 0.1 * k + drift * i:.6g},{np.sin(i / 5):.6g},"
                            f"{np.sin(i / 5):.6g}\n")
        with open(os.path.join(folder, "latent_grid.csv"), "w") as f:
            f.write("z_q,z_p,learned_h,dz_q,dz_p\n")
            for a in np.linspace(-1, 1, 10):
                for b in np.linspace(-1, 1, 10):
                    h = "" if m == "baseline" else f"{a * a + b * b:.6g}"
                    f.write(f"{a:.6g},{b:.6g},{h},{b:.6g},{-a:.6g}\n")
        with open(os.path.join(folder, "latent_paths.csv"), "w") as f:
            f.write("traj,k,z_q,z_p\n")
            for k, r in enumerate((0.3, 0.6)):
                for i in range(30):
                    f.write(f"{k},{i},{r * np.cos(i / 5):.6g},{r * np.sin(i / 5):.6g}\n")
    with open(os.path.join(root, "pixel-pendulum", "hnn", "bump.csv"), "w") as f:
        f.write("phase,t,z_q,z_p,learned_h,energy\n")
        for t in range(60):
            phase = ("symplectic", "riemann", "symplectic-after")[t // 20]
            r = 0.5 + 0.3 * min(max(t - 20, 0), 19) / 19
            f.write(f"{phase},{t},{r * np.cos(t / 5):.6g},{r * np.sin(t / 5):.6g},{r * r:.6g},"
                    f"{1.1 * r * r:.6g}\n")
    strip = np.random.default_rng(0).random((90, 5 * 58 + 2))
    plt.imsave(os.path.join(root, "pixel-pendulum", "rollout_strip.png"), strip, cmap="gray")
    with open(os.path.join(root, "reversibility.json"), "w") as f:
        json.dump([{"task": "pixel-pendulum", "model": m, "volume": {"abs_log_det_mean": 1e-6},
                    "integrators": [{"integrator": name, "return_distance_mean": 1e-7 * (j + 1)}
                                    for j, name in enumerate(["midpoint", "rk4", "dopri5"])]}
                   for m in MODELS], f)


def write_sweep_table(folder, keys, runs):
    """SWEEP_DIR/results.csv as hnn sweep writes it: run, status, reason, the spec's keys, where
    and how long each run ran, then the metrics' keys; runs: (values, status, metrics)."""
    os.makedirs(folder, exist_ok=True)
    metric_keys = sorted({k for _, _, metrics in runs for k in metrics})
    with open(os.path.join(folder, "results.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["run", "status", "reason", *keys, "run_host", "run_seconds", "run_resumed",
                    *metric_keys])
        for i, (values, status, metrics) in enumerate(runs):
            w.writerow([f"{values['task']}/{values['model']}/run{i}", status,
                        "diverged" if status == "failed" else "",
                        *[values.get(k, "") for k in keys], "host", "1.0", "false",
                        *[metrics.get(k, "") for k in metric_keys]])


def png_size(path):
    """(width, height) from the IHDR chunk; raises if the file is not a PNG."""
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise AssertionError(f"{path}: not a PNG")
    return struct.unpack(">II", head[16:24])


EXPECTED = ["fig2_spring", "fig3_two-body", "fig3_three-body", "training_curves",
            "table1_chart"]


class PlotTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.root = os.environ.get("KEEP") or tempfile.mkdtemp(prefix="plot_test_")
        os.makedirs(cls.root, exist_ok=True)
        cls.results = os.path.join(cls.root, "results")
        shutil.rmtree(cls.results, ignore_errors=True)
        os.makedirs(cls.results)
        build_results(cls.results)
        cls.plotted = run_plot(cls.results)
        cls.data = os.path.join(cls.root, "data_runs")
        shutil.rmtree(cls.data, ignore_errors=True)
        cls.data_runs = [write_data_run(os.path.join(cls.data, m), m) for m in MODELS]

    @classmethod
    def tearDownClass(cls):
        if not os.environ.get("KEEP"):
            shutil.rmtree(cls.root, ignore_errors=True)

    def copy_results(self, name):
        folder = os.path.join(self.root, name)
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(self.results, folder,
                        ignore=shutil.ignore_patterns("*.png", "*.svg"))  # inputs only
        return folder

    def test_draws_every_chart_as_png_and_svg(self):
        self.assertEqual(self.plotted.returncode, 0, self.plotted.stderr)
        printed = self.plotted.stdout.split()
        for stem in EXPECTED:
            png = os.path.join(self.results, stem + ".png")
            svg = os.path.join(self.results, stem + ".svg")
            self.assertIn(png, printed)
            self.assertIn(svg, printed)
            width, height = png_size(png)
            self.assertGreater(width, 600, png)
            self.assertGreater(height, 300, png)
            self.assertGreater(os.path.getsize(png), 20_000, png)
            with open(svg) as f:
                self.assertIn("<svg", f.read(2000), svg)

    def test_leaves_no_temporary_files(self):
        leftovers = [n for n in os.listdir(self.results) if n.endswith(".tmp")]
        self.assertEqual(leftovers, [])

    def test_missing_tasks_are_skipped_with_a_note(self):
        self.assertEqual(self.plotted.returncode, 0, self.plotted.stderr)
        for task in ("pendulum", "real-pendulum", "pixel-pendulum"):
            self.assertIn(f"note: {task}: no results, skipped", self.plotted.stderr)
            self.assertFalse(os.path.exists(os.path.join(self.results, f"fig2_{task}.png")))

    def test_missing_model_and_table_still_draw_the_rest(self):
        folder = self.copy_results("partial")
        shutil.rmtree(os.path.join(folder, "spring", "hnn"))
        os.remove(os.path.join(folder, "two-body", "baseline", "rollout.csv"))
        os.remove(os.path.join(folder, "table1.json"))
        run = run_plot(folder)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn("spring/hnn: missing", run.stderr)
        self.assertIn("two-body/baseline/rollout.csv: missing", run.stderr)
        self.assertIn("table1.json: missing", run.stderr)
        for stem in ("fig2_spring", "fig3_two-body", "training_curves"):
            self.assertTrue(os.path.isfile(os.path.join(folder, stem + ".png")), stem)
        self.assertFalse(os.path.exists(os.path.join(folder, "table1_chart.png")))

    def test_malformed_csv_is_an_error_naming_the_file(self):
        folder = self.copy_results("bad_csv")
        path = os.path.join(folder, "spring", "hnn", "rollout.csv")
        with open(path, "a") as f:
            f.write("0,20.1,oops,1\n")
        run = run_plot(folder)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(path, run.stderr)
        self.assertNotIn("Traceback", run.stderr)

    def test_non_numeric_cell_is_an_error_naming_file_and_column(self):
        folder = self.copy_results("bad_cell")
        path = os.path.join(folder, "two-body", "hnn", "loss_curve.csv")
        with open(path, "a") as f:
            f.write("10001,abc,1e-5\n")
        run = run_plot(folder)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(path, run.stderr)
        self.assertIn("train_loss", run.stderr)

    def test_malformed_json_is_an_error_naming_the_file(self):
        folder = self.copy_results("bad_json")
        path = os.path.join(folder, "table1.json")
        with open(path, "w") as f:
            f.write('[{"task": "spring", ')
        run = run_plot(folder)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(path, run.stderr)
        drawn = [n for n in os.listdir(folder) if n.endswith((".png", ".svg"))]
        self.assertEqual(drawn, [], "inputs are all read before any chart is written")

    def test_help_says_what_it_draws(self):
        for script in ("plot.py", "plot_pixel.py", "plot_speed_accuracy.py", "plot_study.py"):
            run = run_plot("--help", script=os.path.join(SCRIPTS, script))
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertIn("usage:", run.stdout)
        self.assertIn("fig2_<task>", run_plot("--help").stdout)

    def test_missing_folder_is_an_error(self):
        run = run_plot(os.path.join(self.root, "does-not-exist"))
        self.assertEqual(run.returncode, 1)
        self.assertIn("not a folder", run.stderr)

    # --runs: Figure 2 of run folders, here of the data task (uneven stretches, d = 4, no H)

    def test_runs_draw_fig2_of_data_runs(self):
        out = os.path.join(self.data, "figures", "new")  # made if missing
        run = run_plot("--runs", *self.data_runs, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertNotIn("Traceback", run.stderr)
        png, svg = os.path.join(out, "fig2_data.png"), os.path.join(out, "fig2_data.svg")
        self.assertEqual(run.stdout.split(), [png, svg])
        width, height = png_size(png)
        self.assertGreater(width, 600)
        self.assertGreater(height, 300)
        self.assertEqual([n for n in os.listdir(out) if n.endswith(".tmp")], [])
        with open(svg) as f:
            text = f.read()
        for words in ("no known Hamiltonian",  # the energy panel says why it has no energy
                      "p_x",  # q_1 against p_1, named from state_names
                      "valid pred. time 4.25", "coord. MSE 3.40e-04",  # from metrics.json
                      "mean while half or more run",  # the stretches differ in length
                      "spread on the training states",  # the scale of the learned H's drift
                      "Data from oscillators.csv: test trajectory 2 (the longest of 3),"
                      " t = 30..35.95"):
            self.assertTrue(words in text, f"{svg} lacks {words!r}")

    def test_runs_sampled_at_different_times_draw_each_rollout(self):
        base = write_data_run(os.path.join(self.data, "uneven", "baseline"), "baseline",
                              steps=(0.05, 0.08, 0.03))
        out = os.path.join(self.data, "uneven")
        run = run_plot("--runs", base, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        with open(os.path.join(out, "fig2_data.svg")) as f:
            text = f.read()
        self.assertTrue("no mean" in text, "each rollout's own line")
        self.assertTrue("no HNN run" in text, "nor a learned H: the energy panel says so")

    def test_runs_with_a_broken_or_missing_file_are_an_error_naming_it(self):
        folder = os.path.join(self.data, "broken")
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(self.data_runs[1], folder)
        path = os.path.join(folder, "rollout.csv")
        with open(path, "a") as f:
            f.write("2,36,oops\n")
        out = os.path.join(self.data, "broken_out")
        run = run_plot("--runs", self.data_runs[0], folder, "--out", out)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(path, run.stderr)
        self.assertNotIn("Traceback", run.stderr)
        self.assertFalse(os.path.exists(out), "nothing is written")
        os.remove(path)
        run = run_plot("--runs", folder, "--out", out)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(f"{path}: missing", run.stderr)

    def test_runs_of_different_tasks_or_data_are_an_error_naming_them(self):
        spring = os.path.join(self.results, "spring", "hnn")
        run = run_plot("--runs", self.data_runs[0], spring, "--out", self.data)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn("different tasks", run.stderr)
        self.assertIn(f"{self.data_runs[0]} (data)", run.stderr)
        self.assertIn(f"{spring} (spring)", run.stderr)
        other = write_data_run(os.path.join(self.data, "other", "hnn"), "hnn",
                               steps=(0.05, 0.05, 0.06))
        run = run_plot("--runs", self.data_runs[0], other, "--out", self.data)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(f"different data: {self.data_runs[0]} and {other}", run.stderr)
        run = run_plot("--runs", self.data_runs[1], other, "--out", self.data)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn("two hnn runs", run.stderr)
        self.assertNotIn("Traceback", run.stderr)


class PixelTest(unittest.TestCase):
    def test_draws_the_pixel_figures_and_reversibility(self):
        root = tempfile.mkdtemp(prefix="plot_pixel_test_")
        try:
            write_pixel_results(root)
            run = run_plot(root, script=os.path.join(SCRIPTS, "plot_pixel.py"))
            self.assertEqual(run.returncode, 0, run.stderr)
            for stem in ("fig4_pixel_pendulum", "figC1_pixel_latent", "fig5_pixel_bump",
                         "reversibility"):
                png = os.path.join(root, stem + ".png")
                self.assertIn(png, run.stdout.split())
                self.assertGreater(png_size(png)[0], 600, png)
            os.remove(os.path.join(root, "pixel-pendulum", "hnn", "bump.csv"))
            run = run_plot(root, script=os.path.join(SCRIPTS, "plot_pixel.py"))
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertIn("bump.csv: missing (run `hnn bump`)", run.stderr)
        finally:
            shutil.rmtree(root, ignore_errors=True)


def size_runs():
    """The model-size study of one task: 200-200 in float and double, widths 16, 32 and 200 with
    seeds 0-2 in double; 16-16 is 3 times worse than 200-200, 32-32 within its noise."""
    runs = []
    for dtype in ("float", "double"):
        for model in MODELS:
            runs.append(({"task": "spring", "model": model, "dtype": dtype, "hidden": "200-200",
                          "seed": 0}, "done",
                         {"test_loss": 0.036, "test_loss_se": 0.002, "energy_mse": 3e-4,
                          "energy_mse_se": 1e-4, "train_seconds": 20.0 if dtype == "double"
                          else 10.0}))
    for hidden, worse, seconds in (("16-16", 3.0, 0.4), ("32-32", 1.02, 1.0),
                                   ("200-200", 1.0, 20.0)):
        for seed in (0, 1, 2):
            if hidden == "200-200" and seed == 0:
                continue  # the float/double part's double run above
            runs.append(({"task": "spring", "model": "hnn", "dtype": "double", "hidden": hidden,
                          "seed": seed}, "done",
                         {"test_loss": 0.036 * worse * (1 + 0.01 * seed), "test_loss_se": 0.002,
                          "energy_mse": 3e-4 * worse, "energy_mse_se": 1e-4,
                          "train_seconds": seconds}))
    runs.append(({"task": "spring", "model": "hnn", "dtype": "double", "hidden": "64-64",
                  "seed": 0}, "failed", {}))
    return runs


class StudyTest(unittest.TestCase):
    def setUp(self):
        self.root = tempfile.mkdtemp(prefix="plot_study_test_")

    def tearDown(self):
        shutil.rmtree(self.root, ignore_errors=True)

    def study(self, *args):
        return run_plot(*args, script=os.path.join(SCRIPTS, "plot_study.py"))

    def test_model_size_draws_charts_3_and_4_and_chooses_the_lean_model(self):
        sweep, out = os.path.join(self.root, "sweep"), os.path.join(self.root, "charts")
        write_sweep_table(sweep, ["task", "model", "dtype", "hidden", "seed"], size_runs())
        run = self.study("model_size", sweep, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn("spring/hnn/run", run.stderr)  # the failed run, noted
        for name in ("float_double.png", "model_size.png", "model_size.csv", "lean.csv"):
            self.assertIn(os.path.join(out, name), run.stdout.split())
        with open(os.path.join(out, "lean.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([(r["config"], r["hidden"], r["params"], r["seeds"]) for r in rows],
                         [("paper", "200-200", "41001", "3"), ("lean", "32-32", "1185", "3")])
        self.assertEqual(rows[1]["speedup_wall"], "20")

    def test_lean_keeps_the_paper_model_when_no_smaller_one_is_within_the_noise(self):
        rows = sweep_table.with_sizes(
            [dict({k: str(v) for k, v in values.items()}, run="r",
                  **{k: str(v) for k, v in metrics.items()})
             for values, status, metrics in size_runs()
             if status == "done" and values["hidden"] != "32-32"], "results.csv")
        stats = lean.config_stats(rows)
        self.assertEqual(lean.choose_lean(stats, "spring")[0], "200-200")
        self.assertEqual(lean.choose_lean(stats, "pendulum"), (None, None))

    def test_a_table_without_the_study_s_columns_is_an_error_naming_it(self):
        sweep = os.path.join(self.root, "sweep")
        write_sweep_table(sweep, ["task", "model"], [({"task": "spring", "model": "hnn"},
                                                      "done", {"test_loss": 1.0})])
        run = self.study("model_size", sweep)
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn(os.path.join(sweep, "results.csv") + ": no column(s) dtype, hidden, seed",
                      run.stderr)
        run = self.study("rollout", os.path.join(self.root, "nowhere"))
        self.assertEqual(run.returncode, 1, run.stderr)
        self.assertIn("results.csv: missing (run `hnn sweep SPEC", run.stderr)

    def test_rollout_table_groups_runs_by_data_and_integrator_and_counts_failures(self):
        keys = ["task", "model", "settings", "seed", "loss", "integrator", "horizon"]
        coarse = '{"sample_dt":1.0,"t_end":6}'
        runs = [({"task": "spring", "model": "hnn", "settings": coarse, "seed": s}, "done",
                 {"stretch_state_mse": v, "truth_leapfrog_state_mse": truth})
                for s, v, truth in ((0, 0.02, 1e-4), (1, 0.04, 3e-4))]
        runs += [({"task": "spring", "model": "hnn", "settings": coarse, "seed": 0,
                   "loss": "rollout", "integrator": "leapfrog", "horizon": 1}, "done",
                  {"stretch_state_mse": 0.005}),
                 ({"task": "spring", "model": "hnn", "settings": coarse, "seed": 1,
                   "loss": "rollout", "integrator": "leapfrog", "horizon": 1}, "failed", {})]
        sweep = os.path.join(self.root, "rollout")
        write_sweep_table(sweep, keys, runs)
        run = self.study("rollout", sweep)
        self.assertEqual(run.returncode, 0, run.stderr)
        with open(os.path.join(sweep, "results.md")) as f:
            text = f.read()
        self.assertIn("| spring-dt1.0 | 0.03 ± 0.01 | 0.005 (1 failed) | 0.0002 ± 0.0001 |", text)
        self.assertIn("| pendulum-dt0.5 | n/a | n/a | n/a |", text)
        self.assertIn("- spring/hnn/run3: diverged", text)

    def test_mean_and_standard_error_over_seeds(self):
        self.assertEqual(sweep_table.mean_se([1.0, 3.0, None]), (2.0, 1.0, 2))
        self.assertEqual(sweep_table.cell([2.0]), "2")
        self.assertEqual(sweep_table.cell([1.0, 3.0]), "2 ± 1")


if __name__ == "__main__":
    unittest.main()
