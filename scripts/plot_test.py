#!/usr/bin/python3
"""Tests scripts/plot.py (the charts of scripts/charts/: fig2, fig3, training_curves, table1) on
the synthetic results folder of scripts/plot_fixtures.py, and its --runs mode (Figure 2 of run
folders) on synthetic runs of the data task. The other commands' tests: plot_pixel_test.py,
plot_study_test.py; ctest runs each as scripts.PlotCharts.<chart> (tests/CMakeLists.txt).

Usage: /usr/bin/python3 scripts/plot_test.py [-v]      (KEEP=DIR keeps the folder in DIR)
"""

import os
import shutil
import tempfile
import unittest

from plot_fixtures import MODELS, SCRIPTS, build_results, png_size, run_plot, write_data_run


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

    def test_a_rollout_csv_not_in_the_one_layout_is_an_error_naming_it(self):
        """rollout.csv is source,traj,t,<state columns>,energy,learned_h with the rows of one
        truth and one model: the old side-by-side layout, or two models, are refused by name."""
        folder = os.path.join(self.data, "old_layout")
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(self.data_runs[1], folder)
        path = os.path.join(folder, "rollout.csv")
        for content, message in (
                ("traj,t,true_0,pred_0,true_energy,pred_energy,learned_h\n0,0,1,1,,,\n",
                 "header lacks column(s) source, energy"),
                ("source,traj,t,q,energy,learned_h\ndata,0,0,1,,\nhnn,0,0,1,,\n"
                 "baseline,0,0,1,,\n", "sources data,hnn,baseline")):
            with open(path, "w") as f:
                f.write(content)
            run = run_plot("--runs", folder, "--out", os.path.join(self.data, "old_out"))
            self.assertEqual(run.returncode, 1, run.stderr)
            self.assertIn(f"{path}: ", run.stderr)
            self.assertIn(message, run.stderr)
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


class Table1HeadroomTest(unittest.TestCase):
    def test_bars_spanning_many_decades_leave_room_for_the_tallest_label(self):
        import numpy as np

        from charts.table1 import headroom
        self.assertEqual(headroom(np.array([1e-3, 1e-1])), 1e3)  # at least 3 decades
        # The three-body baseline's 3.7e+07 over the two-body HNN's 2e-06 (the axis starts at a
        # fifth of it): 14 decades, 4.2 of them above the tallest bar.
        self.assertAlmostEqual(np.log10(headroom(np.array([2e-6, 3.7e7]))), 4.19, places=2)


if __name__ == "__main__":
    unittest.main()
