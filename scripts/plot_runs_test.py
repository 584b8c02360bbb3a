#!/usr/bin/python3
"""Tests the charts of run folders and rollout files (scripts/plot.py --runs, --rollouts:
charts/runs.py, h_contour.py) on the synthetic spring runs of scripts/plot_fixtures.py (a
baseline and an HNN whose learned H is 0.7 E + 0.1, so it must be drawn + 0.092 to equal the
true energy 0.64 at the start of test trajectory 0), and that every script of scripts/ answers
--help without running anything.

Usage: /usr/bin/python3 scripts/plot_runs_test.py [-v]
"""

import glob
import os
import shutil
import subprocess
import tempfile
import unittest

from plot_fixtures import (SCRIPTS, build_results, png_size, run_plot, spring_rollouts,
                           write_paths, write_rollout)


def svg_text(path):
    with open(path) as f:
        return f.read()


class RunChartsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.root = tempfile.mkdtemp(prefix="plot_runs_test_")
        results = os.path.join(cls.root, "results")
        build_results(results)
        cls.base, cls.hnn = (os.path.join(results, "spring", m) for m in ("baseline", "hnn"))
        for model, run in (("baseline", cls.base), ("hnn", cls.hnn)):  # `hnn rollout`'s files
            write_rollout(os.path.join(run, "rollout_dopri5.csv"), *spring_rollouts(model), model)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.root, ignore_errors=True)

    def plot(self, *args):
        run = run_plot(*args)
        self.assertNotIn("Traceback", run.stderr)
        return run

    def assert_drawn(self, out, stems, printed):
        self.assertEqual(printed.split(), [os.path.join(out, f"{s}.{e}") for s in stems
                                           for e in ("png", "svg")])
        for stem in stems:
            width, height = png_size(os.path.join(out, f"{stem}.png"))
            self.assertGreater(width, 500, stem)
            self.assertGreater(height, 300, stem)

    def test_runs_draw_loss_curves_the_h_contour_and_their_rollout_files(self):
        out = os.path.join(self.root, "runs")
        run = self.plot("--runs", self.base, self.hnn, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assert_drawn(out, ["fig2_spring", "training_curves", "h_contour_spring",
                                "rollout_dopri5_spring"], run.stdout)
        contour = svg_text(os.path.join(out, "h_contour_spring.svg"))
        for words in ("True energy E", "Learned H + 0.092: equal to E at the start of test"
                      " trajectory 0", "H is defined only up to a constant"):
            self.assertIn(words, contour)
        fig2 = svg_text(os.path.join(out, "fig2_spring.svg"))
        self.assertIn("H is defined only up to a constant: drawn + 0.092", fig2)
        self.assertIn("Baseline NN, test", svg_text(os.path.join(out, "training_curves.svg")))
        self.assertIn("hnn rollout: rollout_dopri5.csv",
                      svg_text(os.path.join(out, "rollout_dopri5_spring.svg")))

    def test_rollout_files_are_drawn_in_either_layout(self):
        out = os.path.join(self.root, "files")
        older = os.path.join(self.root, "older", "rollout_rk4.csv")  # no metrics.json beside
        os.makedirs(os.path.dirname(older))
        write_paths(older, *spring_rollouts("hnn"), ["q", "p"], "hnn")
        run = self.plot("--rollouts", os.path.join(self.hnn, "rollout_dopri5.csv"), older,
                        "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assert_drawn(out, ["rollout_dopri5_hnn", "h_contour_rollout_dopri5_hnn",
                                "rollout_rk4_hnn", "h_contour_rollout_rk4_hnn"], run.stdout)
        # The same rollouts in both layouts: the same learned H, shifted alike.
        for stem in ("h_contour_rollout_dopri5_hnn", "h_contour_rollout_rk4_hnn"):
            self.assertIn("Learned H + 0.092", svg_text(os.path.join(out, f"{stem}.svg")))

    def test_a_learned_h_without_truth_is_drawn_as_learned(self):
        t, trajs = spring_rollouts("hnn")
        path = os.path.join(self.root, "no_truth", "rollout.csv")
        os.makedirs(os.path.dirname(path))
        write_rollout(path, t, [(x, y, None, None, h) for x, y, _, _, h in trajs], "hnn")
        out = os.path.join(self.root, "no_truth_out")
        run = self.plot("--rollouts", path, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        contour = svg_text(os.path.join(out, "h_contour_rollout_hnn.svg"))
        self.assertIn("Learned H, as learned (defined only up to a constant;", contour)
        self.assertNotIn("True energy", contour)

    def test_an_older_rollout_file_whose_truth_ends_early_is_drawn_up_to_its_end(self):
        t, trajs = spring_rollouts("hnn")
        path = os.path.join(self.root, "short.csv")
        write_paths(path, t, trajs, ["q", "p"], "hnn", truth_rows=40)
        out = os.path.join(self.root, "short_out")
        run = self.plot("--rollouts", path, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn(f"{path}: the truth of 3 trajectories is sampled at other times than the"
                      " model's: drawn interpolated between its samples, and not past its end",
                      run.stderr)
        self.assert_drawn(out, ["short_hnn", "h_contour_short_hnn"], run.stdout)

    def test_runs_and_rollouts_need_out_and_not_both(self):
        for args in (["--runs", self.hnn], ["--rollouts", "x.csv", "--runs", self.hnn,
                                            "--out", self.root]):
            run = self.plot(*args)
            self.assertEqual(run.returncode, 2, run.stderr)
            self.assertIn("--runs or --rollouts takes --out DIR", run.stderr)
        run = self.plot("--rollouts", os.path.join(self.root, "nope.csv"), "--out", self.root)
        self.assertEqual(run.returncode, 1)
        self.assertIn("nope.csv: no such file", run.stderr)


class ScriptHelpTest(unittest.TestCase):
    def test_every_script_answers_help_without_running_anything(self):
        """Each script with --help prints its header and exits 0, with only dirname and sed on
        the PATH: a script that ignored --help would fail for want of cmake, never build."""
        tools = tempfile.mkdtemp(prefix="help_path_")
        try:
            for tool in ("dirname", "sed"):
                os.symlink(shutil.which(tool), os.path.join(tools, tool))
            for script in sorted(glob.glob(os.path.join(SCRIPTS, "*.sh"))):
                run = subprocess.run(["/bin/bash", script, "--help"], capture_output=True,
                                     text=True, timeout=30, env={"PATH": tools})
                self.assertEqual((run.returncode, run.stderr), (0, ""), script)
                self.assertGreater(len(run.stdout.splitlines()), 0, script)
                self.assertNotIn("#", run.stdout.splitlines()[0], script)
        finally:
            shutil.rmtree(tools)


if __name__ == "__main__":
    unittest.main()
