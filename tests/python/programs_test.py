"""The Python package hnn against the hnn program ($HNN_EXE): the same runs, metrics and files.

Run by ctest with PYTHONPATH at the built package (tests/CMakeLists.txt): python.Programs."""

import csv
import json
import os
import signal
import subprocess
import tempfile
import threading
import unittest

import numpy as np

import hnn
from hnn_test import spring_data

HNN_EXE = os.environ.get("HNN_EXE", "hnn")


def run_hnn(*args, cwd):
    result = subprocess.run([HNN_EXE, *args], cwd=cwd, capture_output=True, text=True)
    if result.returncode != 0:
        raise AssertionError(f"hnn {' '.join(args)}: {result.stderr}")
    return result.stdout


class Programs(unittest.TestCase):
    """The package against the hnn program: the same files, the same runs."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.options = ["--steps", "20", "--hidden", "8", "8", "--lr", "0.01", "--quiet"]
        run_hnn("train", "spring", "--out", "cli", *cls.options, cwd=cls.dir)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_train_gives_the_programs_metrics(self):
        hnn.set_threads(1)
        run = hnn.train("spring", out=os.path.join(self.dir, "py"), steps=20, hidden=[8, 8],
                        lr=0.01, quiet=True)
        self.assertEqual(hnn.threads(), 1)  # the run's --threads 2 did not stay
        cli = hnn.load_run(os.path.join(self.dir, "cli"))
        timing = {k for k in cli.metrics if k.endswith("seconds")}
        self.assertTrue(timing)
        same = {k: v for k, v in cli.metrics.items() if k not in timing}
        self.assertEqual({k: v for k, v in run.metrics.items() if k not in timing}, same)
        curve = run.loss_curve
        self.assertEqual(list(curve), ["step", "train_loss", "test_loss"])
        np.testing.assert_array_equal(curve["train_loss"], cli.loss_curve["train_loss"])
        self.assertEqual(run.rollouts["hnn"]["x"].shape[2], 2)
        np.testing.assert_array_equal(run.rollouts["true"]["x"], cli.rollouts["true"]["x"])
        evaluated = json.loads(run_hnn("evaluate", run.path, "--json", cwd=self.dir))
        self.assertEqual(evaluated["test_loss"], run.metrics["test_loss"])  # the program reads it

    def test_train_with_a_sampled_fit_gives_the_programs_metrics(self):
        args = ["--fit", "sampled", "--hidden", "64", "--sampler", "elm", "--quiet"]
        run_hnn("train", "spring", "--out", "cli-sampled", *args, cwd=self.dir)
        run = hnn.train("spring", out=os.path.join(self.dir, "py-sampled"), fit="sampled",
                        hidden=64, sampler="elm", quiet=True)
        cli = hnn.load_run(os.path.join(self.dir, "cli-sampled"))

        def untimed(metrics):
            out = {k: v for k, v in metrics.items() if not k.endswith("seconds")}
            out["fit"] = {k: v for k, v in out["fit"].items() if not k.endswith("seconds")}
            return out
        self.assertEqual(run.metrics["fit"]["method"], "sampled")
        self.assertEqual(run.loss_curve, {})  # no steps, no loss_curve.csv
        self.assertEqual(run.model.kind, "hnn")
        self.assertEqual(untimed(run.metrics), untimed(cli.metrics))

    def test_ctrl_c_stops_train_with_a_checkpoint_the_program_resumes(self):
        out = os.path.join(self.dir, "stopped")
        timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        with self.assertRaises(KeyboardInterrupt):
            hnn.train("spring", out=out, steps=10**6, hidden=[4], quiet=True)
        timer.join()
        self.assertTrue(os.path.isdir(os.path.join(out, "checkpoint")))
        self.assertFalse(os.path.exists(os.path.join(out, "metrics.json")))
        with self.assertRaisesRegex(hnn.Error, "resume"):  # the program's own guard
            hnn.train("spring", out=out, steps=10, quiet=True)

    def test_resume_continues_a_run_as_the_program_does(self):
        base = ["--hidden", "8", "--lr", "0.01", "--quiet"]
        run_hnn("train", "spring", "--out", "cli-more", "--steps", "10", *base, cwd=self.dir)
        run_hnn("train", "--resume", "cli-more", "--steps", "20", "--quiet", cwd=self.dir)
        out = os.path.join(self.dir, "py-more")
        hnn.train("spring", out=out, steps=10, hidden=[8], lr=0.01, quiet=True)
        run = hnn.train(out=out, resume=True, steps=20, quiet=True)
        cli = hnn.load_run(os.path.join(self.dir, "cli-more"))

        def untimed(metrics):
            return {k: v for k, v in metrics.items() if not k.endswith("seconds")}
        self.assertEqual(run.metrics["continued_from"], [10])
        self.assertEqual(untimed(run.metrics), untimed(cli.metrics))
        np.testing.assert_array_equal(run.loss_curve["train_loss"],
                                      cli.loss_curve["train_loss"])
        again = hnn.train(resume=out, steps=30, quiet=True, threads=1)  # resume=DIR
        self.assertEqual(again.metrics["continued_from"], [10, 20])
        for pattern, call in [
                ("lr cannot be combined with resume", lambda: hnn.train(resume=out, lr=0.1)),
                ("task cannot be combined with resume", lambda: hnn.train("spring", resume=out)),
                ("resume=True continues the run in out", lambda: hnn.train(resume=True)),
                ("fewer than the 30 steps", lambda: hnn.train(resume=out, steps=25))]:
            with self.subTest(pattern=pattern):
                with self.assertRaisesRegex(hnn.Error, pattern):
                    call()

    def test_a_model_saved_from_python_runs_in_the_program(self):
        # The run's own model, its weights changed from Python and saved into a copy of the run:
        # the program's rollout of it is the package's.
        run_dir = os.path.join(self.dir, "changed")
        run_hnn("train", "spring", "--out", run_dir, *self.options, cwd=self.dir)
        model = hnn.load_run(run_dir).model
        changed = {k: v * 1.1 for k, v in model.parameters().items()}
        model.set_parameters(changed)
        model.save(os.path.join(run_dir, "params.bin"))
        run_hnn("rollout", run_dir, "--state", "0.5,0.1", "--integrator", "rk4", "--dt", "0.01",
                "--t-end", "0.5", "--points", "6", "--out", "r.csv", cwd=self.dir)
        with open(os.path.join(self.dir, "r.csv"), newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["source"] == "hnn"]
        program = np.array([[float(r["x_0"]), float(r["x_1"])] for r in rows])
        ours = hnn.load(os.path.join(run_dir, "params.bin")).rollout(
            [[0.5, 0.1]], np.linspace(0, 0.5, 6), integrator="rk4", dt=0.01)[:, 0, :]
        np.testing.assert_allclose(ours, program, rtol=1e-10, atol=1e-12)

    def test_load_reads_the_programs_params(self):
        params = os.path.join(self.dir, "cli", "params.bin")
        model = hnn.load(params)
        self.assertEqual((model.kind, model.dim), ("hnn", 2))
        x, _ = spring_data(5)
        np.testing.assert_array_equal(model.vector_field(x),
                                      hnn.load_run(os.path.join(self.dir, "cli")).model
                                      .vector_field(x))

    def test_load_reads_a_mass_hnns_two_networks(self):
        # Finzi et al.'s HNN: V and the mass factor, both MLPs of the chain's two angles.
        run_hnn("train", "chain-pendulum-2", "--model", "hnn-mass", "--out", "mass", "--steps",
                "2", "--hidden", "6", "--batch", "4", "--dtype", "double", "--quiet",
                "--settings", '{"trajectories": 4, "validation": 2, "rollouts": 2}', cwd=self.dir)
        run_dir = os.path.join(self.dir, "mass")
        model = hnn.load(os.path.join(run_dir, "params.bin"), angles=2)
        self.assertEqual((model.kind, model.dim), ("hnn-mass", 4))
        x = np.array([[0.3, -0.2, 0.1, 0.5], [1.0, 2.0, -0.4, 0.2]])
        field = model.vector_field(x)
        np.testing.assert_array_equal(field[:, :2], x[:, 2:])  # dq/dt = v
        np.testing.assert_array_equal(field, hnn.load_run(run_dir).model.vector_field(x))
        self.assertEqual(model.hamiltonian(x).shape, (2,))


if __name__ == "__main__":
    unittest.main()
