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

import numpy as np

from plot_fixtures import (SCRIPTS, build_results, png_size, run_plot, spring_rollouts,
                           write_paths, write_rollout)


def svg_text(path):
    with open(path) as f:
        return f.read()


def file_valid_time(model, threshold=0.1):
    """The valid prediction time of spring_rollouts(model), computed here: the mean time until
    |x^ - x| / (|x^| + |x|) first passes the threshold."""
    t, trajs = spring_rollouts(model)
    times = []
    for true, pred, _, _, _ in trajs:
        error = np.linalg.norm(pred - true, axis=1) / (np.linalg.norm(pred, axis=1)
                                                       + np.linalg.norm(true, axis=1))
        past = np.nonzero(~(error[1:] <= threshold))[0]
        times.append(t[past[0] + 1] if len(past) else t[-1])
    return float(np.mean(times)) - t[0]


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
        paths = svg_text(os.path.join(out, "rollout_dopri5_spring.svg"))
        self.assertIn("hnn rollout: rollout_dopri5.csv", paths)
        # The legend quotes the file's own rollouts, not the run's test rollouts (4.25).
        self.assertNotIn("valid pred. time 4.25", paths)
        self.assertIn(f"valid pred. time {file_valid_time('hnn'):.3g} (these 3 rollouts)", paths)
        t, trajs = spring_rollouts("hnn")
        mse = np.mean([np.mean((e - f) ** 2) for _, _, e, f, _ in trajs])
        self.assertIn(f"HNN {mse:.2e})", paths)  # not the run's 3.84e-04

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

    def test_a_loss_curve_in_standardised_units_says_so_on_its_chart(self):
        """A data run's loss_curve.csv names its columns train_loss_standardised and
        test_loss_standardised: read as the loss, and labelled in those units."""
        copy = os.path.join(self.root, "standardised", "hnn")
        shutil.copytree(self.hnn, copy)
        path = os.path.join(copy, "loss_curve.csv")
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(text.replace("step,train_loss,test_loss",
                                 "step,train_loss_standardised,test_loss_standardised", 1))
        out = os.path.join(self.root, "standardised_out")
        run = self.plot("--runs", copy, "--out", out)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn("(standardised units)", svg_text(os.path.join(out, "training_curves.svg")))
        run = self.plot("--runs", self.hnn, "--out", os.path.join(self.root, "plain_out"))
        self.assertNotIn("standardised", svg_text(os.path.join(self.root, "plain_out",
                                                               "training_curves.svg")))

    def test_runs_and_rollouts_need_out_and_not_both(self):
        for args in (["--runs", self.hnn], ["--rollouts", "x.csv", "--runs", self.hnn,
                                            "--out", self.root]):
            run = self.plot(*args)
            self.assertEqual(run.returncode, 2, run.stderr)
            self.assertIn("--runs or --rollouts takes --out DIR", run.stderr)
        run = self.plot("--rollouts", os.path.join(self.root, "nope.csv"), "--out", self.root)
        self.assertEqual(run.returncode, 1)
        self.assertIn("nope.csv: no such file", run.stderr)


# A stand-in for `hnn hamiltonian` (found through $HNN): it records its arguments and writes the
# grid of a two-body state whose true energy is E = |x|^2 / 2 and whose learned H is E - 0.25,
# so that the slice must be drawn + 0.25.
FAKE_HNN = """#!/usr/bin/python3
import sys
args = sys.argv[1:]
open(sys.argv[0] + ".args", "w").write(" ".join(args))
opt = dict(zip(args[2::2], args[3::2]))
axes = [(i.split("=")[0], *map(float, i.split("=")[1].split(":"))) for i in opt["--grid"].split(",")]
held = [(i.split("=")[0], float(i.split("=")[1])) for i in opt["--at"].split(",")]
n = int(opt["--points"])
rows = [",".join([axes[0][0], axes[1][0], *(h[0] for h in held), "learned_h", "energy"])]
for j in range(n):
    for i in range(n):
        a = axes[0][1] + (axes[0][2] - axes[0][1]) * i / (n - 1)
        b = axes[1][1] + (axes[1][2] - axes[1][1]) * j / (n - 1)
        e = 0.5 * (a * a + b * b + sum(v * v for _, v in held))
        rows.append(",".join(map(repr, [a, b, *(v for _, v in held), e - 0.25, e])))
open(opt["--out"], "w").write("\\n".join(rows) + "\\n")
"""


class SliceChartTest(unittest.TestCase):
    """More than one degree of freedom: plot.py --runs draws the learned H on a 2-D slice from
    `hnn hamiltonian`'s grid, or from a grid CSV given with --h-grid."""

    @classmethod
    def setUpClass(cls):
        cls.root = tempfile.mkdtemp(prefix="plot_slice_test_")
        build_results(os.path.join(cls.root, "results"))
        cls.runs = [os.path.join(cls.root, "results", "two-body", m) for m in ("baseline", "hnn")]
        cls.hnn = os.path.join(cls.root, "hnn")
        with open(cls.hnn, "w") as f:
            f.write(FAKE_HNN)
        os.chmod(cls.hnn, 0o755)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.root, ignore_errors=True)

    def assert_slice(self, out, run):
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertNotIn("Traceback", run.stderr)
        self.assertIn(os.path.join(out, "h_slice_two-body.png"), run.stdout.split())
        width, height = png_size(os.path.join(out, "h_slice_two-body.png"))
        self.assertGreater(width, 500)
        svg = svg_text(os.path.join(out, "h_slice_two-body.svg"))
        for words in ("True energy E", "Learned H + 0.25 (the best constant on this grid)",
                      "H is defined only up to a constant"):
            self.assertIn(words, svg)
        self.assertIn("the learned H is drawn + 0.25,", run.stderr)

    def test_runs_of_more_degrees_of_freedom_draw_the_slice_of_hnn_hamiltonian(self):
        out = os.path.join(self.root, "out")
        run = run_plot("--runs", *self.runs, "--out", out, env={"HNN": self.hnn})
        self.assert_slice(out, run)
        with open(self.hnn + ".args") as f:
            args = f.read().split()
        # The first coordinate and its momentum; the other six held at the shown start.
        self.assertEqual(args[:2], ["hamiltonian", self.runs[1]])
        grid = args[args.index("--grid") + 1]
        self.assertRegex(grid, r"^x_0=[-0-9.e]+:[-0-9.e]+,x_4=[-0-9.e]+:[-0-9.e]+$")
        self.assertEqual(len(args[args.index("--at") + 1].split(",")), 6)
        self.assertIn(os.path.join(out, "h_grid_two-body.csv"), run.stdout.split())
        self.assertIn("q1 (x_0)", svg_text(os.path.join(out, "h_slice_two-body.svg")))

    def test_a_grid_csv_is_drawn_without_the_hnn_program(self):
        out = os.path.join(self.root, "given")
        made = os.path.join(self.root, "made")
        os.makedirs(made)
        grid = os.path.join(made, "grid.csv")
        subprocess.run([self.hnn, "hamiltonian", "RUN", "--grid", "x=-1:1,px=-2:2", "--at",
                        "y=0.5", "--points", "7", "--out", grid], check=True)
        run = run_plot("--runs", *self.runs, "--out", out, "--h-grid", grid,
                       env={"HNN": os.path.join(self.root, "missing")})
        self.assert_slice(out, run)
        self.assertIn("y = 0.5", svg_text(os.path.join(out, "h_slice_two-body.svg")))

    def test_a_grid_that_is_not_one_is_an_error(self):
        bad = os.path.join(self.root, "bad.csv")
        with open(bad, "w") as f:
            f.write("x,px,learned_h,energy\n0,0,1,1\n1,0,1,1\n0,1,1,1\n")
        run = run_plot("--runs", *self.runs, "--out", os.path.join(self.root, "bad"),
                       "--h-grid", bad)
        self.assertEqual(run.returncode, 1)
        self.assertIn("3 rows are not a grid of 2 x 2 points of x and px", run.stderr)


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
