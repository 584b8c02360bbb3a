// hamiltonian_derivatives (physics/autodiff/): each system's H written with the engine's ops
// equals its hamiltonian_batch and gives its field; derivatives of higher order match central
// differences of the order below, and the closed forms (Pendulum's engine twin and the same H
// as an ExpressionSystem, differentiated by GiNaC); bad calls are refused by name.
#include "physics/autodiff/hamiltonian_derivatives.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "physics/double_pendulum.h"
#include "physics/expression_system.h"
#include "physics/henon_heiles.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"

namespace hnn::physics {
namespace {

using ::testing::HasSubstr;

std::vector<std::shared_ptr<System>> systems() {
  return {std::make_shared<Spring>(2.0, 0.5),
          std::make_shared<Pendulum>(3.0, 0.7),
          std::make_shared<NBody>(std::vector<double>{1.0, 2.0, 0.5}, 1.3),
          std::make_shared<DoublePendulum>(1.0, 2.0, 1.0, 0.5, 9.81),
          std::make_shared<DoublePendulum>(1.0, 1.0, 1.0, 1.0, 9.81,
                                           DoublePendulum::PotentialZero::kAtPivot),
          std::make_shared<HenonHeiles>(0.8),
          std::make_shared<ExpressionSystem>("p1^2/2 + p2^2/3 + q1^2*q2 + exp(q1)*sin(q2*p1)",
                                             std::vector<std::string>{"q1", "q2"},
                                             std::vector<std::string>{"p1", "p2"})};
}

Batch states_of(const System& s) {
  std::mt19937_64 rng(7);
  return s.sample_initial_states(3, rng);
}

// d/dx_j of column block `entries` of f(x), by central differences: R x (entries * dim), each
// new index last, as hamiltonian_derivatives lays them out.
Batch central_difference(const System& s, const Batch& x, int order, double eps = 1e-6) {
  const Eigen::Index dim = x.cols();
  const Batch f0 = hamiltonian_derivatives(s, x, order);
  Batch out(x.rows(), f0.cols() * dim);
  for (Eigen::Index j = 0; j < dim; ++j) {
    Batch plus = x, minus = x;
    plus.col(j).array() += eps;
    minus.col(j).array() -= eps;
    const Batch d =
        (hamiltonian_derivatives(s, plus, order) - hamiltonian_derivatives(s, minus, order)) /
        (2.0 * eps);
    for (Eigen::Index e = 0; e < f0.cols(); ++e) out.col(e * dim + j) = d.col(e);
  }
  return out;
}

TEST(HamiltonianDerivatives, OrderZeroIsHAndOrderOneIsTheField) {
  for (const auto& s : systems()) {
    SCOPED_TRACE(s->name());
    const Batch x = states_of(*s);
    const Eigen::VectorXd h = s->hamiltonian_batch(x);
    const Batch h0 = hamiltonian_derivatives(*s, x, 0);
    EXPECT_LT((h0.col(0) - h).cwiseAbs().maxCoeff(), 1e-13 * (1.0 + h.cwiseAbs().maxCoeff()));
    Batch f;
    s->vector_field(x, f);
    const Batch g = hamiltonian_derivatives(*s, x, 1);
    const Eigen::Index n = x.cols() / 2;
    Batch expected(x.rows(), x.cols());
    expected << -f.rightCols(n), f.leftCols(n);  // dH/dq = -dp/dt, dH/dp = dq/dt
    EXPECT_LT((g - expected).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + f.cwiseAbs().maxCoeff()));
  }
}

TEST(HamiltonianDerivatives, HigherOrdersMatchDifferencesOfTheOrderBelow) {
  for (const auto& s : systems()) {
    SCOPED_TRACE(s->name());
    const Batch x = states_of(*s);
    for (int order = 1; order <= 3; ++order) {
      const Batch d = hamiltonian_derivatives(*s, x, order);
      const Batch fd = central_difference(*s, x, order - 1);
      ASSERT_EQ(d.cols(), fd.cols());
      EXPECT_LT((d - fd).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + d.cwiseAbs().maxCoeff()))
          << "order " << order;
    }
  }
}

TEST(HamiltonianDerivatives, ClosedForms) {
  const Batch x = (Batch(2, 2) << 0.3, -0.2, 1.1, 0.5).finished();
  // Spring(2, 0.5): H = 2 q^2 + 0.5 p^2, Hessian diag(4, 1), nothing beyond.
  const Spring spring(2.0, 0.5);
  const Batch h2 = hamiltonian_derivatives(spring, x, 2);
  for (Eigen::Index r = 0; r < 2; ++r)
    EXPECT_EQ(h2.row(r), (Eigen::RowVector4d() << 4.0, 0.0, 0.0, 1.0).finished());
  EXPECT_EQ(hamiltonian_derivatives(spring, x, 3), Batch::Zero(2, 8));
  // H = 3 (1 - cos q) + p^2, the class and the formula: d^k/dq^k = 3 (sin, cos, -sin, -cos).
  const Pendulum pendulum(3.0, 1.0);
  const ExpressionSystem formula("3*(1 - cos(q)) + p^2", {"q"}, {"p"});
  for (const System* s :
       {static_cast<const System*>(&pendulum), static_cast<const System*>(&formula)}) {
    for (int k = 1; k <= 4; ++k) {
      const Batch d = hamiltonian_derivatives(*s, x, k);
      for (Eigen::Index r = 0; r < 2; ++r) {
        const double q = x(r, 0);
        const double expected[] = {3 * std::sin(q), 3 * std::cos(q), -3 * std::sin(q),
                                   -3 * std::cos(q)};
        EXPECT_NEAR(d(r, 0), expected[k - 1], 1e-14) << s->name() << ", order " << k;
        const double along_p = k == 1 ? 2 * x(r, 1) : k == 2 ? 2.0 : 0.0;  // H's p^2
        EXPECT_NEAR(d(r, d.cols() - 1), along_p, 1e-14);
      }
    }
  }
}

TEST(HamiltonianDerivatives, RefusesByName) {
  const Batch x = Batch::Zero(2, 2);
  const auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_THAT(message([&] { hamiltonian_derivatives(Spring(), Batch::Zero(2, 4), 1); }),
              HasSubstr("spring: state has 4 columns, expected 2"));
  EXPECT_THAT(message([&] { hamiltonian_derivatives(Spring(), x, -1); }),
              HasSubstr("derivative of order -1"));
  EXPECT_THAT(message([&] { hamiltonian_derivatives(DampedSpring(0.1), x, 2); }),
              HasSubstr("has no derivatives beyond the field's"));
  const ExpressionSystem log_q("log(q) + p^2", {"q"}, {"p"});
  EXPECT_THAT(message([&] { hamiltonian_derivatives(log_q, x, 2); }),
              HasSubstr("d^2 H / dq dq is"));
}

}  // namespace
}  // namespace hnn::physics
