// The sampled-HNN paper's systems: Hénon–Heiles against its formula and its invariants, the
// double pendulum's potential zero at the pivot, and the uniform box sampler.
#include "physics/henon_heiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "physics/double_pendulum.h"
#include "physics/integrator.h"
#include "physics/simulate.h"
#include "physics_test_util.h"

namespace hnn::physics {
namespace {

TEST(HenonHeiles, HamiltonianIsThePapersFormula) {
  Batch x(2, 4);
  x << 0.3, -0.2, 0.5, 0.1,  //
      -4.0, 3.0, 2.0, -5.0;
  const double alpha = 0.7;
  const Eigen::VectorXd h = HenonHeiles(alpha).hamiltonian_batch(x);
  for (Eigen::Index i = 0; i < 2; ++i) {
    const double q1 = x(i, 0), q2 = x(i, 1), p1 = x(i, 2), p2 = x(i, 3);
    const double expected = (p1 * p1 + p2 * p2) / 2 + (q1 * q1 + q2 * q2) / 2 +
                            alpha * (q1 * q1 * q2 - q2 * q2 * q2 / 3);
    EXPECT_NEAR(h(i), expected, 1e-13 * std::max(1.0, std::abs(expected)));
  }
}

TEST(HenonHeiles, FieldMatchesFiniteDifferencesOnThePapersBox) {
  std::mt19937_64 rng(3);
  const HenonHeiles system;
  const Batch x = system.sample_initial_states(200, rng);
  Batch exact;
  system.vector_field(x, exact);
  const Batch fd = testing::symplectic_gradient_fd(system, x, 1e-5);
  EXPECT_LT((exact - fd).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff(), 1e-8);
}

// Below the escape energy 1/6 the motion is bounded and H is conserved; the cubic term's
// symmetry under rotation by 120 degrees in (q1, q2) leaves H unchanged.
TEST(HenonHeiles, ConservesEnergyAndHasItsThreefoldSymmetry) {
  const HenonHeiles system;
  Batch x0(1, 4);
  x0 << 0.1, -0.1, 0.2, 0.15;
  ASSERT_LT(system.hamiltonian(x0.row(0)), 1.0 / 6.0);
  const Trajectory path = simulate(system, x0, linspace(0.0, 50.0, 11));
  EXPECT_LT(testing::max_in(testing::relative_energy_errors(system, path), 0, 11), 1e-7);

  const double c = std::cos(2 * std::numbers::pi / 3), s = std::sin(2 * std::numbers::pi / 3);
  std::mt19937_64 rng(8);
  const Batch x = system.sample_initial_states(50, rng);
  Batch turned = x;
  turned.col(0) = c * x.col(0) - s * x.col(1);
  turned.col(1) = s * x.col(0) + c * x.col(1);
  EXPECT_LT((system.hamiltonian_batch(turned) - system.hamiltonian_batch(x)).cwiseAbs().maxCoeff(),
            1e-11);
}

TEST(HenonHeiles, SamplesItsBoxAndRefusesBadConstants) {
  std::mt19937_64 rng(4);
  const Batch x = HenonHeiles(1.0, 2.5).sample_initial_states(4000, rng);
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 2.5);
  EXPECT_GT(x.cwiseAbs().maxCoeff(), 2.45);
  EXPECT_NEAR(x.mean(), 0.0, 0.05);
  EXPECT_THROW(HenonHeiles(-1.0), std::invalid_argument);
  EXPECT_THROW(HenonHeiles(1.0, 0.0), std::invalid_argument);
}

TEST(DoublePendulum, PotentialZeroAtThePivotShiftsHOnly) {
  const DoublePendulum rest(1, 1, 1, 1, 1),
      pivot(1, 1, 1, 1, 1, DoublePendulum::PotentialZero::kAtPivot);
  std::mt19937_64 rng(5);
  const Batch x = rest.sample_initial_states(20, rng);
  // (m1 + m2) g l1 + m2 g l2 = 3 with unit constants.
  EXPECT_LT((rest.hamiltonian_batch(x).array() - pivot.hamiltonian_batch(x).array() - 3.0)
                .abs()
                .maxCoeff(),
            1e-12);
  Batch a, b;
  rest.vector_field(x, a);
  pivot.vector_field(x, b);
  EXPECT_EQ(a, b);
  // The paper's H at q = p = 0: -(m1 + m2) g l1 - m2 g l2.
  EXPECT_DOUBLE_EQ(pivot.hamiltonian(Eigen::RowVector4d::Zero()), -3.0);
}

TEST(SampleBox, EachColumnInItsRangeAndTheSameSeedTheSameStates) {
  const std::vector<ValueRange> box = {{-1.0, 2.0}, {5.0, 5.5}};
  std::mt19937_64 a(1), b(1);
  const Batch x = sample_box(500, box, a);
  EXPECT_GE(x.col(0).minCoeff(), -1.0);
  EXPECT_LE(x.col(0).maxCoeff(), 2.0);
  EXPECT_GE(x.col(1).minCoeff(), 5.0);
  EXPECT_LE(x.col(1).maxCoeff(), 5.5);
  EXPECT_EQ(sample_box(3, box, b), x.topRows(3));
}

}  // namespace
}  // namespace hnn::physics
