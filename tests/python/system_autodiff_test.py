"""hnn.autodiff on hnn.systems: a system's H differentiated to any order
(physics/autodiff/hamiltonian_derivatives.h), against closed forms and central differences.

Run by ctest under pytest with PYTHONPATH at the built package (tests/CMakeLists.txt):
python.SystemAutodiff."""

import unittest

import numpy as np

import hnn
from hnn_test import central_difference


def systems():
    return {
        "Spring": hnn.systems.Spring(2.0, 0.5),
        "Pendulum": hnn.systems.Pendulum(3.0, 0.7),
        "NBody": hnn.systems.NBody(3, masses=[1.0, 2.0, 0.5], gravity=1.3),
        "DoublePendulum": hnn.systems.DoublePendulum(m2=2.0, l2=0.5),
        "Expression": hnn.systems.Expression("p1^2/2 + p2^2/3 + q1^2*q2 + exp(q1)*sin(q2*p1)",
                                             ["q1", "q2"], ["p1", "p2"]),
    }


class SystemAutodiff(unittest.TestCase):
    def test_derivatives_match_the_field_and_differences(self):
        for name, system in systems().items():
            with self.subTest(system=name):
                x = system.initial_states(3, seed=5)
                dim, n = system.dim, system.dim // 2
                d = [hnn.autodiff.derivative(system, x, k) for k in range(4)]
                self.assertEqual([a.shape for a in d], [(3,) + (dim,) * k for k in range(4)])
                np.testing.assert_allclose(d[0], system.hamiltonian(x), rtol=1e-13)
                f = system.vector_field(x)
                np.testing.assert_allclose(d[1], np.hstack([-f[:, n:], f[:, :n]]),
                                           rtol=1e-12, atol=1e-12)
                for k in range(1, 4):
                    order = k - 1
                    fd = central_difference(
                        lambda v: hnn.autodiff.derivative(system, v, order), x)
                    np.testing.assert_allclose(d[k], fd, rtol=1e-6, atol=1e-6)
                np.testing.assert_array_equal(hnn.autodiff.grad(system, x), d[1])
                np.testing.assert_array_equal(hnn.autodiff.hessian(system, x), d[2])
                np.testing.assert_allclose(d[3], d[3].transpose(0, 2, 3, 1), rtol=1e-12,
                                           atol=1e-12)  # mixed partials commute

    def test_closed_forms(self):
        x = np.array([[0.3, -0.2], [1.1, 0.5]])
        spring = hnn.systems.Spring(2.0, 0.5)  # H = 2 q^2 + p^2 / 2
        np.testing.assert_array_equal(hnn.autodiff.hessian(spring, x),
                                      np.broadcast_to(np.diag([4.0, 1.0]), (2, 2, 2)))
        np.testing.assert_array_equal(hnn.autodiff.derivative(spring, x, 5), 0.0)
        q = x[:, 0]
        along_q = [3 * np.sin(q), 3 * np.cos(q), -3 * np.sin(q), -3 * np.cos(q)]
        for system in (hnn.systems.Pendulum(3.0, 1.0),
                       hnn.systems.Expression("3*(1 - cos(q)) + p^2", ["q"], ["p"])):
            for k in range(1, 5):
                d = hnn.autodiff.derivative(system, x, k)
                np.testing.assert_allclose(d[(slice(None),) + (0,) * k], along_q[k - 1],
                                           rtol=1e-14, atol=1e-15)
                along_p = [2 * x[:, 1], 2.0, 0.0, 0.0][k - 1]  # H's p^2
                np.testing.assert_array_equal(d[(slice(None),) + (1,) * k], along_p)

    def test_what_it_refuses(self):
        spring = hnn.systems.Spring()
        with self.assertRaisesRegex(hnn.Error, "order must be 0 to 6, got 7"):
            hnn.autodiff.derivative(spring, np.zeros((1, 2)), 7)
        with self.assertRaisesRegex(hnn.Error, r"x: expected 2 columns \(q then p\)"):
            hnn.autodiff.hessian(spring, np.zeros((1, 4)))
        with self.assertRaisesRegex(hnn.Error, "d\\^2 H / dq dq is -inf at state 0"):
            hnn.autodiff.hessian(hnn.systems.Expression("log(q) + p^2", ["q"], ["p"]),
                                 [[0.0, 0.0]])
        with self.assertRaisesRegex(hnn.Error, "expected an hnn.Model or a system, got str"):
            hnn.autodiff.grad("spring", np.zeros((1, 2)))


if __name__ == "__main__":
    unittest.main()
