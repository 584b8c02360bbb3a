// Higher-order derivatives against closed forms and finite differences: third derivatives,
// Hessians and Hessian-vector products, the task Hamiltonians' gradients, and the HNN training
// gradient (a gradient through a gradient) of the paper's 2-200-200-1 model.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_matrix;
using VarD = Var<double>;

namespace {

// The n-th derivative of f at each entry of x0, by n nested grad() calls (f is elementwise, so
// the gradient of sum(f(x)) is f'(x) entry by entry).
MatrixD NthDerivative(const std::function<VarD(const VarD&)>& f, const MatrixD& x0, int n) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  VarD d = f(x);
  for (int k = 1; k <= n; ++k) {
    d = ad::grad<double>({ad::sum(d)}, {x}, {.create_graph = k < n})[0];
  }
  return d.value();
}

MatrixD Points() {
  MatrixD x(1, 7);
  x << -2.5, -1.2, -0.4, 0.0, 0.3, 0.9, 1.7;
  return x;
}

TEST(ThirdDerivative, OfSinIsMinusCos) {
  const MatrixD x = Points();
  const MatrixD d3 = NthDerivative([](const VarD& v) { return ad::sin(v); }, x, 3);
  EXPECT_TRUE(d3.isApprox(MatrixD(-x.array().cos()), 1e-14)) << d3;
}

TEST(ThirdDerivative, OfExpIsExp) {
  const MatrixD x = Points();
  const MatrixD d3 = NthDerivative([](const VarD& v) { return ad::exp(v); }, x, 3);
  EXPECT_TRUE(d3.isApprox(MatrixD(x.array().exp()), 1e-14)) << d3;
}

TEST(ThirdDerivative, OfTanhIsMinusTwoSech2TimesOneMinusThreeTanh2) {
  // t' = 1 - t^2 = s, t'' = -2 t s, t''' = -2 (s^2 - 2 t^2 s) = -2 s (1 - 3 t^2).
  const MatrixD x = Points();
  const MatrixD d3 = NthDerivative([](const VarD& v) { return ad::tanh(v); }, x, 3);
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    const double t = std::tanh(x(0, i)), s = 1 - t * t;
    EXPECT_NEAR(d3(0, i), -2 * s * (1 - 3 * t * t), 1e-13) << "at x = " << x(0, i);
  }
}

TEST(NthDerivative, OfSinIsAPhaseShiftToAnyOrder) {
  // d^n/dx^n sin x = sin(x + n pi / 2).
  const MatrixD x = Points();
  for (int n = 1; n <= 6; ++n) {
    const MatrixD dn = NthDerivative([](const VarD& v) { return ad::sin(v); }, x, n);
    const MatrixD expected = (x.array() + n * std::numbers::pi / 2).sin().matrix();
    EXPECT_LT((dn - expected).cwiseAbs().maxCoeff(), 1e-13) << "order " << n;
  }
}

TEST(NthDerivative, OfAQuarticEndsInAConstant) {
  // (x^2)^2 -> 4x^3 -> 12x^2 -> 24x -> 24; and x^4 by pow -> 12x^2 at second order.
  const MatrixD d4 =
      NthDerivative([](const VarD& v) { return ad::square(ad::square(v)); }, Points(), 4);
  EXPECT_TRUE(d4.isApprox(MatrixD::Constant(1, 7, 24.0), 1e-14)) << d4;
  const MatrixD x = random_matrix(1, 5, 1, 0.5, 2);
  const MatrixD d2 = NthDerivative([](const VarD& v) { return ad::pow(v, 4.0); }, x, 2);
  EXPECT_TRUE(d2.isApprox(12 * x.array().square().matrix(), 1e-13));
}

TEST(Hessian, OfQuadraticFormIsAPlusATransposed) {
  const MatrixD a = random_matrix(5, 5, 2);     // not symmetric
  const auto quadratic = [&a](const VarD& x) {  // x A x^T, x a 1x5 row
    return ad::sum(x * ad::matmul(x, VarD::constant(a)));
  };
  const MatrixD h = ad::hessian<double>(quadratic, random_matrix(1, 5, 3));
  EXPECT_TRUE(h.isApprox(a + a.transpose(), 1e-14)) << h;
}

// A small tanh MLP energy summed over a batch.
struct SmallMlp {
  std::vector<MatrixD> params = ad::testing::mlp_parameters({3, 8, 8, 1}, 4);
  VarD operator()(const VarD& x) const {
    std::vector<VarD> p;
    for (const MatrixD& m : params) p.push_back(VarD::constant(m));
    return ad::sum(ad::testing::mlp(p, x));
  }
};

MatrixD AutodiffGradient(const SmallMlp& f, const MatrixD& x0) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  return ad::grad<double>({f(x)}, {x})[0].value();
}

TEST(Hessian, OfTanhMlpMatchesFiniteDifferencesOfItsGradient) {
  const SmallMlp f;
  const MatrixD x0 = random_matrix(2, 3, 5);  // a batch of two rows, flattened row-major
  const MatrixD h = ad::hessian<double>(f, x0);
  ASSERT_EQ(h.rows(), 6);
  constexpr double kStep = 1e-5;
  MatrixD numeric(6, 6);
  for (Eigen::Index j = 0; j < 6; ++j) {
    MatrixD plus = x0, minus = x0;
    plus.data()[j] += kStep;
    minus.data()[j] -= kStep;
    numeric.col(j) =
        (AutodiffGradient(f, plus) - AutodiffGradient(f, minus)).reshaped<Eigen::RowMajor>() /
        (2 * kStep);
  }
  EXPECT_LT((h - numeric).cwiseAbs().maxCoeff(), 1e-8) << h << "\n\n" << numeric;
  EXPECT_GT(h.cwiseAbs().maxCoeff(), 1e-2);  // not trivially zero
  EXPECT_TRUE(h.isApprox(h.transpose(), 1e-12));
  // Rows of the batch do not interact: the cross blocks are exactly zero.
  EXPECT_TRUE(h.block(0, 3, 3, 3).isZero(0.0));
  EXPECT_TRUE(h.block(3, 0, 3, 3).isZero(0.0));
}

TEST(Hessian, VectorProductEqualsHessianTimesVector) {
  const SmallMlp f;
  const auto g = [&f](const VarD& x) { return f(x) + ad::sum(ad::sin(x) * ad::exp(x)); };
  const MatrixD x0 = random_matrix(2, 3, 6), v = random_matrix(2, 3, 7);
  const MatrixD h = ad::hessian<double>(g, x0);
  const MatrixD hv = ad::hvp<double>(g, x0, v);
  const Eigen::VectorXd expected = h * v.reshaped<Eigen::RowMajor>();
  EXPECT_TRUE(hv.reshaped<Eigen::RowMajor>().isApprox(expected, 1e-13));
}

TEST(Hessian, OfALinearFunctionIsZero) {
  const auto f = [](const VarD& x) { return ad::sum(ad::scale(x, 3.0)); };
  const MatrixD x0 = random_matrix(1, 4, 19);
  EXPECT_TRUE(ad::hessian<double>(f, x0).isZero(0.0));
  EXPECT_TRUE(ad::hvp<double>(f, x0, random_matrix(1, 4, 20)).isZero(0.0));
}

TEST(DoubleBackward, GivesAJacobianVectorProductThroughTheSeed) {
  // g(v) = J^T v is linear in the seed v, so d<g(v), u>/dv = J u: forward mode from reverse.
  ad::TapeScope scope;
  const MatrixD a = random_matrix(3, 2, 21), u0 = random_matrix(1, 3, 22);
  const VarD x = VarD::leaf(random_matrix(1, 3, 23));
  const VarD y = ad::tanh(ad::matmul(x, VarD::constant(a)));  // 1x2
  const VarD v = VarD::leaf(MatrixD::Zero(1, 2));             // any value: g is linear in v
  const VarD g = ad::grad<double>({y}, {x}, {.create_graph = true}, {v})[0];
  const VarD jvp = ad::grad<double>({ad::sum(g * VarD::constant(u0))}, {v})[0];
  const MatrixD j = ad::jacobian<double>(
      [&a](const VarD& z) { return ad::tanh(ad::matmul(z, VarD::constant(a))); }, x.value());
  EXPECT_TRUE(jvp.value().transpose().isApprox(j * u0.transpose(), 1e-14));
}

TEST(Jacobian, OfALinearMapIsItsMatrix) {
  const MatrixD a = random_matrix(3, 4, 8);
  const MatrixD j = ad::jacobian<double>(
      [&a](const VarD& x) { return ad::matmul(x, VarD::constant(a)); }, random_matrix(1, 3, 9));
  EXPECT_TRUE(j.isApprox(a.transpose(), 1e-15));  // d(xA)_i / dx_k = A_ki
}

// ---- the task Hamiltonians ---------------------------------------------------------------

MatrixD Gradient(const std::function<VarD(const VarD&)>& h, const MatrixD& x0) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  return ad::grad<double>({ad::sum(h(x))}, {x})[0].value();
}

TEST(Hamiltonians, SpringGradientIsAnalytic) {
  const MatrixD x = random_matrix(20, 2, 10);
  EXPECT_TRUE(Gradient(ad::testing::spring_h<double>, x)
                  .isApprox(ad::testing::spring_grad<double>(x), 1e-15));
}

TEST(Hamiltonians, PendulumGradientIsAnalytic) {
  const MatrixD x = random_matrix(20, 2, 11, -3, 3);
  EXPECT_TRUE(Gradient(ad::testing::pendulum_h<double>, x)
                  .isApprox(ad::testing::pendulum_grad<double>(x), 1e-15));
}

TEST(Hamiltonians, TwoBodyGradientIsAnalytic) {
  // States as the task draws them: body 1 at pos ~ U[0.5, 1.5]^2, body 2 at -pos, and momenta
  // near the circular orbit's.
  const MatrixD pos = random_matrix(20, 2, 12, 0.5, 1.5), noise = random_matrix(20, 4, 13);
  MatrixD x(20, 8);
  for (Eigen::Index i = 0; i < 20; ++i) {
    const double r = pos.row(i).norm(), vx = -pos(i, 1) / (2 * std::pow(r, 1.5)),
                 vy = pos(i, 0) / (2 * std::pow(r, 1.5));
    x.row(i) << pos(i, 0), -pos(i, 0), pos(i, 1), -pos(i, 1), vx, -vx, vy, -vy;
    x.row(i).tail(4) += 0.05 * noise.row(i);
  }
  const MatrixD g = Gradient(ad::testing::two_body_h<double>, x);
  EXPECT_TRUE(g.isApprox(ad::testing::two_body_grad<double>(x), 1e-14));
  // Newton's third law: the forces on the two bodies cancel.
  EXPECT_LT((g.col(0) + g.col(1)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((g.col(2) + g.col(3)).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Hamiltonians, SymplecticFieldOfTheSpringIsItsExactMotion) {
  // J grad H for H = q^2 + p^2 gives dq/dt = 2p, dp/dt = -2q (docs/tasks.md, task 1).
  ad::TapeScope scope;
  const MatrixD x0 = random_matrix(10, 2, 14);
  const VarD x = VarD::leaf(x0);
  const VarD dh = ad::grad<double>({ad::sum(ad::testing::spring_h(x))}, {x})[0];
  const VarD field = ad::concat_cols<double>({ad::slice_cols(dh, 1, 1), -ad::slice_cols(dh, 0, 1)});
  EXPECT_TRUE(field.value().col(0).isApprox(2 * x0.col(1)));
  EXPECT_TRUE(field.value().col(1).isApprox(-2 * x0.col(0)));
}

// ---- the HNN training gradient of the paper's model --------------------------------------

TEST(HnnTrainingGradient, Of2x200x200x1TanhMlpMatchesFiniteDifferences) {
  const std::vector<MatrixD> values = ad::testing::mlp_parameters({2, 200, 200, 1}, 15);
  const MatrixD x0 = random_matrix(16, 2, 16), target = random_matrix(16, 2, 17);
  std::vector<VarD> params = ad::testing::as_leaves<double>(values);

  std::vector<MatrixD> analytic;
  {
    ad::TapeScope scope;
    const VarD loss = ad::testing::hnn_loss(params, VarD::leaf(x0), VarD::constant(target));
    // The output bias shifts H by a constant: it does not reach the field, so it is unused.
    for (const VarD& g : ad::grad<double>({loss}, params, {.allow_unused = true}))
      analytic.push_back(g.value());
  }
  const auto loss_value = [&] {
    ad::TapeScope scope;
    return ad::testing::hnn_loss(params, VarD::leaf(x0), VarD::constant(target)).item();
  };

  // Central differences on a random subset of the 40,000+ weights: 25 entries of each tensor.
  constexpr double kStep = 1e-5;
  std::mt19937_64 rng(18);
  double largest = 0;
  for (std::size_t k = 0; k < params.size(); ++k) {
    MatrixD& w = params[k].mutable_value();
    std::uniform_int_distribution<Eigen::Index> pick(0, w.size() - 1);
    for (int sample = 0; sample < 25; ++sample) {
      const Eigen::Index e = pick(rng);
      const double w0 = w.data()[e];
      w.data()[e] = w0 + kStep;
      const double plus = loss_value();
      w.data()[e] = w0 - kStep;
      const double minus = loss_value();
      w.data()[e] = w0;
      const double numeric = (plus - minus) / (2 * kStep), exact = analytic[k].data()[e];
      EXPECT_NEAR(exact, numeric, 1e-10 + 1e-6 * std::abs(numeric))  // seen: ~3e-12
          << "parameter " << k << " entry " << e;
      largest = std::max(largest, std::abs(numeric));
    }
  }
  EXPECT_GT(largest, 1e-3);  // the sampled gradient entries are not all negligible
  EXPECT_TRUE(analytic.back().isZero(0.0));
}

}  // namespace
