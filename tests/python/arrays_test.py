"""NumPy arrays into the package hnn (apps/python/arrays.cpp): other layouts and dtypes give
what their C-order float64 copies give, converted in one copy; bad arrays give one message each.

Run by ctest under pytest with PYTHONPATH at the built package (tests/CMakeLists.txt):
python.Arrays."""

import tracemalloc
import unittest

import numpy as np

import hnn

X = np.array([[0.1, 0.2], [0.3, -0.4], [0.5, 0.6], [-0.7, 0.8]])


def variants(x):
    """x in other layouts and dtypes, each equal in value to x."""
    wide = np.zeros((2 * x.shape[0], 3 * x.shape[1]))
    wide[::2, ::3] = x
    return {"fortran": np.asfortranarray(x), "sliced": wide[::2, ::3],
            "float32": x.astype(np.float32),
            "int64": np.rint(10 * x).astype(np.int64), "int16": np.rint(10 * x).astype(np.int16),
            "big-endian": x.astype(">f8"), "reversed": x[::-1], "list": x.tolist()}


class Arrays(unittest.TestCase):
    def assert_same_as_copy(self, f):
        for name, v in variants(X).items():
            with self.subTest(layout=name):
                copy = np.ascontiguousarray(np.asarray(v), dtype=np.float64)
                np.testing.assert_array_equal(f(v), f(copy))

    def test_models_and_systems_take_any_layout(self):
        model = hnn.HNN(2, hidden=(8,), seed=0)
        spring = hnn.systems.Spring()
        for f in (model.vector_field, model.hamiltonian, spring.vector_field, spring.hamiltonian,
                  hnn.HNN(2, hidden=(8,), dtype="float32").vector_field,
                  lambda x: hnn.autodiff.grad(model, x),
                  lambda x: model.rollout(x, [0, 0.5], integrator="rk4", dt=0.1),
                  lambda x: spring.simulate(x, np.array([0, 1])),
                  lambda x: hnn.HNN(2, hidden=(8,), seed=3).fit(x, x, steps=3)):
            self.assert_same_as_copy(f)

    def test_c_contiguous_arrays_of_the_dtype_are_read_in_place(self):
        # The package counts the state arrays it copies (arrays.cpp, states()): a C-contiguous
        # array of the computation's dtype is read in place, any other converted once, with the
        # same results to the bit.
        model, spring = hnn.HNN(2, hidden=(8,), seed=0), hnn.systems.Spring()
        x = np.random.default_rng(1).standard_normal((64, 2))
        float32 = hnn.HNN(2, hidden=(8,), dtype="float32", seed=0)
        for name, f, v in [("field", model.vector_field, x), ("H", model.hamiltonian, x),
                           ("grad", lambda a: hnn.autodiff.grad(model, a), x),
                           ("jacobian", lambda a: hnn.autodiff.jacobian(model, a), x),
                           ("system field", spring.vector_field, x),
                           ("system H", spring.hamiltonian, x),
                           ("system hessian", lambda a: hnn.autodiff.hessian(spring, a), x),
                           ("float32 field", float32.vector_field, x.astype(np.float32))]:
            with self.subTest(call=name):
                before = hnn._hnn._state_copies()
                in_place = f(v)
                self.assertEqual(hnn._hnn._state_copies(), before)
                copied = f(np.asfortranarray(v))
                self.assertEqual(hnn._hnn._state_copies(), before + 1)
                np.testing.assert_array_equal(in_place, copied)
        before = hnn._hnn._state_copies()
        float32.vector_field(x)  # float64 into a float32 model: converted
        self.assertEqual(hnn._hnn._state_copies(), before + 1)

    def test_states_are_copied_once(self):
        # NumPy's allocations are traced, the engine's are not: a Fortran-order or sliced
        # float64 array, and an int64 one, must not be converted by NumPy before the copy
        # into the engine. The peak is then H's result alone, a quarter of x's size.
        model = hnn.HNN(4, hidden=(2,))
        x = np.asfortranarray(np.random.default_rng(0).standard_normal((50_000, 4)))
        for name, v in {"fortran": x, "sliced": np.repeat(x, 2, axis=1)[:, ::2],
                        "int64": np.ones((50_000, 4), dtype=np.int64)}.items():
            with self.subTest(layout=name):
                tracemalloc.start()
                model.hamiltonian(v)
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
                self.assertLess(peak, 0.5 * x.nbytes)

    def test_bad_arrays_give_one_message_each(self):
        model = hnn.HNN(2, hidden=(4,))
        x = X
        t = np.linspace(0, 1, 3)
        paths = np.zeros((3, 2, 2))
        paths[1, 0, 0] = np.nan
        cases = [
            (r"dxdt: expected 2 columns \(q then p\), got shape \(4, 3\)",
             lambda: model.fit(x, np.zeros((4, 3)), steps=1)),
            (r"dxdt: expected a 2-D array \[batch, 2\], got shape \(4, 2, 1\)",
             lambda: model.fit(x, np.zeros((4, 2, 1)), steps=1)),
            ("x: expected an array of numbers, got dtype <U1",
             lambda: model.fit([["a", "b"]], x, steps=1)),
            ("x0: expected an array of numbers, got dtype object",
             lambda: model.rollout(np.array([[None, 1]], dtype=object), [0, 1])),
            (r"x0: the array is empty \(no rows\)", lambda: model.rollout(np.zeros((0, 2)), t)),
            ("dxdt: NaN or infinity at row 2, column 1",
             lambda: model.fit(x, np.where(np.arange(8).reshape(4, 2) == 5, np.nan, x), steps=1)),
            ("t: NaN or infinity", lambda: model.rollout(x, [0, np.inf])),
            (r"t: the array is empty \(no times\)", lambda: model.rollout(x, [])),
            ("trajectories: NaN or infinity at time 1 of trajectory 0",
             lambda: model.fit(paths, t, loss="rollout", steps=1)),
            (r"trajectories: the array is empty \(no trajectories\)",
             lambda: model.fit(np.zeros((3, 0, 2)), t, loss="rollout", steps=1)),
            ("x: expected an array of numbers, got dtype bool",
             lambda: hnn.systems.Spring().hamiltonian(np.ones((2, 2), dtype=bool))),
        ]
        before = model.parameters()
        for pattern, call in cases:
            with self.subTest(pattern=pattern):
                with self.assertRaisesRegex(hnn.Error, pattern) as caught:
                    call()
                self.assertNotIn("\n", str(caught.exception))
        for name, value in model.parameters().items():  # nothing half-trained
            np.testing.assert_array_equal(value, before[name])


if __name__ == "__main__":
    unittest.main()
