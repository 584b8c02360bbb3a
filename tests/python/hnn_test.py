"""The Python package hnn (apps/python/) on small models; against the hnn program:
programs_test.py.

Run by ctest with PYTHONPATH at the built package (tests/CMakeLists.txt): python.Models,
python.Autodiff, python.Types, python.Errors, python.Systems."""

import ast
import os
import signal
import subprocess
import sys
import tempfile
import threading
import unittest

import numpy as np

import hnn

def spring_data(n=64, seed=1):
    spring = hnn.systems.Spring()
    x = spring.initial_states(n, seed=seed)
    return x, spring.vector_field(x)


class Models(unittest.TestCase):
    def test_fit_lowers_the_loss(self):
        x, dxdt = spring_data()
        for make in (hnn.HNN, hnn.Baseline, hnn.DHNN):
            model = make(2, hidden=(16, 16), seed=3)
            losses = model.fit(x, dxdt, steps=60, lr=1e-2)
            self.assertEqual(losses.shape, (60,))
            self.assertLess(losses[-1], 0.2 * losses[0], make.__name__)

    def test_fit_through_an_integrator_lowers_the_loss(self):
        spring = hnn.systems.Spring()
        t = np.linspace(0, 2, 21)
        paths = spring.simulate(spring.initial_states(16, seed=0), t)
        for integrator in ("leapfrog", "rk4"):
            model = hnn.HNN(2, hidden=(16, 16), seed=0)
            losses = model.fit(paths, t, loss="rollout", horizon=3, integrator=integrator,
                               steps=60, lr=1e-2, batch=32)
            self.assertLess(losses[-1], 0.2 * losses[0], integrator)

    def test_sampled_fit_solves_without_steps(self):
        x, dxdt = spring_data(400)
        for make in (hnn.HNN, hnn.Baseline):
            model = make(2, hidden=(100,), seed=0)
            before = np.mean((model.vector_field(x) - dxdt) ** 2)
            losses = model.fit(x, dxdt, fit="sampled", seed=1)
            self.assertEqual(losses.shape, (1,))
            self.assertAlmostEqual(losses[0], np.mean((model.vector_field(x) - dxdt) ** 2))
            self.assertLess(losses[0], 1e-4 * before, make.__name__)
        again = hnn.HNN(2, hidden=(100,), seed=0)
        self.assertEqual(again.fit(x, dxdt, fit="sampled", seed=1)[0],
                         hnn.HNN(2, hidden=(100,), seed=0).fit(x, dxdt, fit="sampled",
                                                                seed=1)[0])
        tuned = hnn.HNN(2, hidden=(100,), seed=0).fit(x, dxdt, fit="sampled+adam", steps=3,
                                                       lr=1e-6, sampler="elm", solver="qr")
        self.assertEqual(tuned.shape, (3,))
        # A given SWIM scale reaches the solve: another scale, another fit.
        steep, smooth = (hnn.HNN(2, hidden=(100,), seed=0).fit(x, dxdt, fit="sampled", seed=1,
                                                               swim_scale=s)[0]
                         for s in (0.549, 0.05))
        self.assertNotEqual(steep, smooth)

    def test_fit_is_seeded_and_batched(self):
        x, dxdt = spring_data()
        runs = [hnn.HNN(2, hidden=8, seed=0).fit(x, dxdt, steps=10, batch=16, seed=s,
                                                     record_every=5) for s in (0, 0, 1)]
        self.assertEqual(runs[0].shape, (2,))
        np.testing.assert_array_equal(runs[0], runs[1])
        self.assertFalse(np.array_equal(runs[0], runs[2]))

    def test_fit_reports_progress(self):
        x, dxdt = spring_data()
        seen = []
        losses = hnn.HNN(2, hidden=(8,)).fit(x, dxdt, steps=9, record_every=4,
                                              callback=lambda step, loss: seen.append((step, loss)))
        self.assertEqual([s for s, _ in seen], [4, 8, 9])
        np.testing.assert_array_equal([l for _, l in seen], losses)

        def stop(step, loss):
            raise StopIteration(f"enough at {step}")
        with self.assertRaisesRegex(StopIteration, "enough at 2"):
            hnn.HNN(2, hidden=(8,)).fit(x, dxdt, steps=9, callback=stop, record_every=2)

    def test_ctrl_c_stops_fit_after_a_step(self):
        # SIGINT sent at step 5 (from the callback, so at a known step): fit raises
        # KeyboardInterrupt with the model as a fit of 5 steps leaves it.
        x, dxdt = spring_data()

        def interrupt(step, loss):
            if step == 5:
                os.kill(os.getpid(), signal.SIGINT)
        stopped = hnn.HNN(2, hidden=(8, 8), seed=0)
        with self.assertRaises(KeyboardInterrupt):
            stopped.fit(x, dxdt, steps=10**7, lr=1e-2, callback=interrupt)
        five = hnn.HNN(2, hidden=(8, 8), seed=0)
        five.fit(x, dxdt, steps=5, lr=1e-2)
        for name, value in five.parameters().items():
            np.testing.assert_array_equal(stopped.parameters()[name], value)
        with self.assertRaises(KeyboardInterrupt):  # Python's own handler is back
            os.kill(os.getpid(), signal.SIGINT)
            threading.Event().wait(5)

    def test_float32_models_compute_in_float32(self):
        x, dxdt = spring_data()
        model = hnn.HNN(2, hidden=(8, 8), dtype="float32")
        self.assertEqual(model.dtype, "float32")
        self.assertEqual(model.vector_field(x).dtype, np.float32)
        self.assertEqual(model.parameters()["mlp.layers.0.weight"].dtype, np.float32)
        losses = model.fit(x, dxdt, steps=20, lr=1e-2)
        self.assertLess(losses[-1], losses[0])

    def test_hnn_field_is_the_symplectic_gradient_of_its_h(self):
        model = hnn.HNN(2, hidden=(8, 8), seed=2)
        x = np.array([[0.3, -0.2], [1.0, 0.5]])
        eps = 1e-6
        dh = [(model.hamiltonian(x + eps * e) - model.hamiltonian(x - eps * e)) / (2 * eps)
              for e in np.eye(2)]
        np.testing.assert_allclose(model.vector_field(x), np.stack([dh[1], -dh[0]], axis=1),
                                   rtol=1e-6, atol=1e-8)

    def test_save_load_round_trip(self):
        model = hnn.DHNN(2, hidden=(8, 8), seed=5)
        x, _ = spring_data(8)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "params.bin")
            model.save(path)
            loaded = hnn.load(path)
        self.assertEqual((loaded.kind, loaded.dim, loaded.dtype),
                         ("hnn-dissipative", 2, "float64"))
        for name, value in model.parameters().items():
            np.testing.assert_array_equal(loaded.parameters()[name], value)
        np.testing.assert_array_equal(loaded.vector_field(x), model.vector_field(x))

    def test_set_parameters_all_or_none(self):
        a, b = hnn.HNN(2, hidden=(4,), seed=0), hnn.HNN(2, hidden=(4,), seed=1)
        x, _ = spring_data(4)
        b.set_parameters(a.parameters())
        np.testing.assert_array_equal(a.vector_field(x), b.vector_field(x))
        bad = a.parameters()
        bad["mlp.layers.1.weight"] = np.zeros((3, 1))
        before = b.parameters()["mlp.layers.0.weight"].copy()
        with self.assertRaisesRegex(hnn.Error, "'mlp.layers.1.weight' must be an array of 4 x 1"):
            b.set_parameters({**bad, "mlp.layers.0.weight": np.ones((2, 4))})
        np.testing.assert_array_equal(b.parameters()["mlp.layers.0.weight"], before)

    def test_rollout_of_a_fitted_field_follows_the_system(self):
        x, dxdt = spring_data(128)
        model = hnn.HNN(2, hidden=(32, 32), seed=0)
        model.fit(x, dxdt, steps=300, lr=1e-2)
        t = np.linspace(0, 1, 11)
        x0 = np.array([[0.5, 0.0]])
        pred = model.rollout(x0, t, integrator="rk4", dt=0.01)
        true = hnn.systems.Spring().simulate(x0, t)
        self.assertEqual(pred.shape, (11, 1, 2))
        self.assertLess(np.abs(pred - true).max(), 0.05)


def central_difference(f, x, eps=1e-6):
    """d f / dx_j at each row of x by central differences, stacked on a new last axis."""
    return np.stack([(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(x.shape[1])],
                    axis=-1)


class Autodiff(unittest.TestCase):
    x = np.array([[0.3, -0.2, 0.1, 0.7], [1.0, 0.5, -0.4, 0.2]])

    def test_model_derivatives_to_third_order_match_differences(self):
        for model in (hnn.HNN(4, hidden=(8, 8), seed=1), hnn.LNN(4, hidden=(8,), seed=2),
                      hnn.DHNN(4, hidden=(8,), seed=3)):
            d = [hnn.autodiff.derivative(model, self.x, k) for k in range(4)]
            self.assertEqual([a.shape for a in d], [(2,), (2, 4), (2, 4, 4), (2, 4, 4, 4)])
            for k in range(3):
                order = k
                fd = central_difference(
                    lambda x: hnn.autodiff.derivative(model, x, order), self.x)
                np.testing.assert_allclose(d[k + 1], fd, rtol=1e-6, atol=1e-8)
            np.testing.assert_array_equal(hnn.autodiff.grad(model, self.x), d[1])
            np.testing.assert_array_equal(hnn.autodiff.hessian(model, self.x), d[2])
        hnn_model = hnn.HNN(4, hidden=(8,), seed=4)
        np.testing.assert_array_equal(hnn.autodiff.derivative(hnn_model, self.x, 0),
                                      hnn_model.hamiltonian(self.x))

    def test_field_jacobian_and_system_gradient_match_differences(self):
        for model in (hnn.HNN(4, hidden=(8,), seed=1), hnn.Baseline(4, hidden=(8,), seed=1)):
            np.testing.assert_allclose(hnn.autodiff.jacobian(model, self.x),
                                       central_difference(model.vector_field, self.x),
                                       rtol=1e-6, atol=1e-8)
        pendulum = hnn.systems.DoublePendulum()
        np.testing.assert_allclose(hnn.autodiff.grad(pendulum, self.x),
                                   central_difference(pendulum.hamiltonian, self.x),
                                   rtol=1e-6, atol=1e-8)

    def test_what_it_refuses(self):
        with self.assertRaisesRegex(hnn.Error, "a baseline model learns no scalar H or L"):
            hnn.autodiff.grad(hnn.Baseline(4, hidden=(4,)), self.x)
        with self.assertRaisesRegex(hnn.Error, "order must be 0 to 6, got 7"):
            hnn.autodiff.derivative(hnn.HNN(4, hidden=(4,)), self.x, 7)


class Types(unittest.TestCase):
    def test_the_pyi_names_every_public_member(self):
        with open(os.path.join(os.path.dirname(hnn.__file__), "_hnn.pyi")) as f:
            tree = ast.parse(f.read())
        named = {n.name for n in ast.walk(tree)
                 if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
        named |= {n.target.id for n in ast.walk(tree) if isinstance(n, ast.AnnAssign)}
        members = [hnn._hnn, hnn.Model, hnn._hnn._FitSpec, hnn._hnn._systems,
                   hnn.systems.System]
        public = {name for m in members for name in vars(m)
                  if not (name.startswith("__") or name in ("doc",))}
        self.assertEqual(public - named - {"systems", "_systems"} - set(dir(object)), set())


    def test_the_type_hint_files_name_every_public_name(self):
        def pyi_names(pyi):
            with open(os.path.join(os.path.dirname(hnn.__file__), pyi + ".pyi")) as f:
                tree = ast.parse(f.read())
            names = {n.name for n in ast.walk(tree)
                     if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
            names |= {n.target.id for n in ast.walk(tree) if isinstance(n, ast.AnnAssign)}
            names |= {t.id for n in ast.walk(tree) if isinstance(n, ast.Assign)
                      for t in n.targets}
            return names | {a.asname for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                            for a in n.names if a.asname}

        for module, pyi in ((hnn, "__init__"), (hnn.systems, "systems"),
                             (hnn.autodiff, "autodiff"), (hnn.runs, "runs")):
            with self.subTest(module=pyi):
                self.assertEqual(set(module.__all__) - pyi_names(pyi), set())
        run_members = {n for n in vars(hnn.Run) if not n.startswith("_")} | {"path", "metrics"}
        self.assertEqual(run_members - pyi_names("runs"), set())

    def test_every_public_name_has_a_docstring(self):
        modules = [hnn, hnn.systems, hnn.autodiff]
        names = [(m.__name__, n, getattr(m, n)) for m in modules for n in m.__all__]
        names += [("hnn.Model", n, getattr(hnn.Model, n)) for n in vars(hnn.Model)
                  if not n.startswith("_")]
        names += [("hnn.Run", n, getattr(hnn.Run, n)) for n in vars(hnn.Run)
                  if not n.startswith("_")]
        names += [("System", n, getattr(hnn.systems.System, n))
                  for n in vars(hnn.systems.System) if not n.startswith("_")]
        missing = [f"{m}.{n}" for m, n, v in names
                   if not (getattr(v, "__doc__", None) or "").strip()]
        self.assertEqual(missing, [])

    def test_works_without_matplotlib_or_a_display(self):
        code = ("import sys; sys.modules['matplotlib'] = None\n"
                "import hnn\n"
                "m = hnn.HNN(2, hidden=(4,))\n"
                "m.fit([[0.1, 0.2], [0.3, 0.4]], [[1.0, 0.0], [0.0, 1.0]], steps=2)\n"
                "print(m.vector_field([[0.0, 1.0]]).shape)\n")
        env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND")}
        result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                text=True)
        self.assertEqual((result.returncode, result.stdout.strip()), (0, "(1, 2)"),
                         result.stderr)


class Errors(unittest.TestCase):
    def setUp(self):
        self.model = hnn.HNN(2, hidden=(4,))

    def expect(self, pattern, call, *args, **kwargs):
        with self.assertRaisesRegex(hnn.Error, pattern) as caught:
            call(*args, **kwargs)
        self.assertNotIn("\n", str(caught.exception))
        self.assertIsInstance(caught.exception, ValueError)

    def test_bad_states(self):
        f = self.model.vector_field
        self.expect(r"x: expected 2 columns \(q then p\), got shape \(3, 3\)", f, np.zeros((3, 3)))
        self.expect(r"x: expected a 2-D array \[batch, 2\], got shape \(2,\)", f, np.zeros(2))
        self.expect("x: expected an array of numbers, got dtype <U1", f, [["a", "b"]])
        self.expect("x: expected an array of numbers, got dtype object", f,
                    np.array([[None, 1]], dtype=object))
        self.expect(r"x: the array is empty \(no rows\)", f, np.zeros((0, 2)))
        self.expect("x: NaN or infinity at row 1, column 0", f, [[0, 0], [np.nan, 0]])
        self.expect("x: NaN or infinity", f, [[np.inf, 0]])

    def test_bad_model_calls(self):
        x, dxdt = spring_data(8)
        self.expect("dxdt: expected 8 rows", self.model.fit, x, dxdt[:4], steps=1)
        self.expect("batch must be 0", self.model.fit, x, dxdt, steps=1, batch=9)
        self.expect("a baseline model learns no H", hnn.Baseline(2, hidden=(4,)).hamiltonian, x)
        self.expect("dtype must be float32 or float64", hnn.HNN, 2, dtype="half")
        self.expect("activation", hnn.HNN, 2, activation="cube")
        self.expect("t: expected a 1-D array of times", self.model.rollout, x, [[0, 1]])
        self.expect("integrator", self.model.rollout, x, [0, 1], integrator="magic")
        paths, t = np.zeros((5, 2, 2)), np.linspace(0, 1, 5)
        self.expect(r"trajectories: expected a 3-D array \[5 times, batch, 2\], got shape "
                    r"\(5, 2\)", self.model.fit, paths[:, 0], t, loss="rollout")
        self.expect("horizon of 9 steps is past the end", self.model.fit, paths, t,
                    loss="rollout", horizon=9)
        self.expect("integrator 'euler'", self.model.fit, paths, t, loss="rollout",
                    integrator="euler")
        self.expect("loss must be derivative or rollout", self.model.fit, paths, t, loss="l2")
        self.expect("fit: horizon is not taken with loss='derivative'", self.model.fit, x, dxdt,
                    horizon=2)
        self.expect("fit: unknown option 'stepz'", self.model.fit, x, dxdt, stepz=2)
        self.expect("fit: steps is not taken with fit='sampled'", self.model.fit, x, dxdt,
                    fit="sampled", steps=3)
        self.expect("sampler applies to a sampled fit only", self.model.fit, x, dxdt,
                    sampler="elm")
        self.expect("--swim-scale must be auto or a finite number > 0, got -1", self.model.fit,
                    x, dxdt, fit="sampled", swim_scale=-1)
        self.expect("unknown fit method 'magic'", self.model.fit, x, dxdt, fit="magic")
        self.expect("does not fit an lnn", hnn.LNN(2, hidden=(4,)).fit, x, dxdt, fit="sampled")
        self.expect("loss='rollout' trains with fit='adam' only", self.model.fit, paths, t,
                    loss="rollout", fit="sampled")
        params = self.model.parameters()
        params["mlp.layers.0.bias"][0, 1] = np.nan
        self.expect("set_parameters: mlp.layers.0.bias: NaN or infinity at row 0, column 1",
                    self.model.set_parameters, params)
        self.expect("unknown parameter 'w'", self.model.set_parameters, {"w": np.zeros((1, 1))})

    def test_bad_files(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "params.bin")
            with open(path, "w") as f:
                f.write("not a parameter file")
            self.expect("parameter file", hnn.load, path)
            self.expect("parameter file", hnn.load, os.path.join(tmp, "missing.bin"))
            self.expect("not a run folder", hnn.load_run, tmp)

    def test_train_options(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "run")
            self.expect(r"unknown option 'stepz' of hnn train \(options: model, steps",
                        hnn.train, "spring", out=out, stepz=3)
            self.expect("steps: expected an integer >= 1, got 0", hnn.train, "spring", out=out,
                        steps=0)
            self.expect("unknown model 'hnnn'", hnn.train, "spring", model="hnnn", out=out)
            self.expect("coords applies to the data task only", hnn.train, "spring", out=out,
                        coords=["q"])
            self.expect("json: not taken from Python", hnn.train, "spring", out=out, json=True)
            self.assertFalse(os.path.exists(out))


class Systems(unittest.TestCase):
    def test_simulate_conserves_h(self):
        cases = [(hnn.systems.Spring(), [[0.5, 0.2]]), (hnn.systems.Pendulum(), [[1.0, 0.0]]),
                 (hnn.systems.DoublePendulum(), [[0.3, -0.2, 0.1, 0.0]]),
                 (hnn.systems.NBody(2), hnn.systems.NBody(2).initial_states(1, seed=0)),
                 (hnn.systems.Expression("p^2/2 + 9.81*(1 - cos(q))", coords=["q"],
                                         momenta=["p"]), [[1.0, 0.5]])]
        t = np.linspace(0, 2, 21)
        for system, x0 in cases:
            path = system.simulate(np.array(x0, dtype=float), t, rtol=1e-10)
            self.assertEqual(path.shape, (21, 1, system.dim))
            h = np.array([system.hamiltonian(state)[0] for state in path])
            self.assertLess(np.abs(h - h[0]).max(), 1e-7 * max(1.0, abs(h[0])), system.name)

    def test_expression_matches_the_library_pendulum(self):
        expr = hnn.systems.Expression("3*(1 - cos(q)) + p^2", coords=["q"], momenta=["p"])
        x = hnn.systems.Pendulum().initial_states(5, seed=2)
        np.testing.assert_allclose(expr.vector_field(x), hnn.systems.Pendulum().vector_field(x),
                                   rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(expr.hamiltonian(x), hnn.systems.Pendulum().hamiltonian(x),
                                   rtol=1e-12)

    def test_symplectic_integrators(self):
        spring = hnn.systems.Spring()
        x0 = np.array([[1.0, 0.0]])
        path = spring.simulate(x0, np.linspace(0, 50, 6), integrator="leapfrog", dt=0.05)
        h = spring.hamiltonian(path[:, 0, :])
        self.assertLess(np.abs(h - 1).max(), 5e-3)  # bounded, not drifting
        with self.assertRaisesRegex(hnn.Error, "x0: expected 2 columns"):
            spring.simulate(np.zeros((1, 3)), [0, 1])
        with self.assertRaisesRegex(hnn.Error, "leapfrog needs a separable Hamiltonian"):
            hnn.systems.DoublePendulum().simulate(np.zeros((1, 4)), [0, 1], integrator="leapfrog")


if __name__ == "__main__":
    unittest.main()
