#!/usr/bin/python3
"""Tests scripts/plot_study.py (scripts/charts/: model_size, float_double, lean, rollout_table,
sweep_table) on synthetic tables of hnn sweep (results.csv): the lean choice and the results
tables.

Usage: /usr/bin/python3 scripts/plot_study_test.py [-v]
"""

import csv
import os
import shutil
import tempfile
import unittest

from charts import lean, sweep_table  # the package beside this file
from plot_fixtures import MODELS, SCRIPTS, run_plot


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
