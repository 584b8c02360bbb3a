// Systems: each field against finite differences of its H, the samplers
// against docs/tasks.md, closed forms and conversions.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "physics/double_pendulum.h"
#include "physics/gym_pendulum.h"
#include "physics/henon_heiles.h"
#include "physics/integrator.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"
#include "physics_test_util.h"

namespace hnn::physics {
namespace {

std::vector<std::shared_ptr<System>> all_systems() {
  return {std::make_shared<Spring>(),
          std::make_shared<Spring>(3.0, 0.5),
          std::make_shared<Pendulum>(),
          std::make_shared<Pendulum>(2.4),
          std::make_shared<GymPendulum>(),
          std::make_shared<NBody>(NBody::equal_masses(2)),
          std::make_shared<NBody>(NBody::equal_masses(3)),
          std::make_shared<NBody>(std::vector<double>{1.0, 2.0, 0.5}, 0.7),
          std::make_shared<DoublePendulum>(),
          std::make_shared<DoublePendulum>(1.5, 0.7, 0.8, 1.3, 3.0),
          std::make_shared<DoublePendulum>(1.0, 1.0, 1.0, 1.0, 1.0,
                                           DoublePendulum::PotentialZero::kAtPivot),
          std::make_shared<HenonHeiles>(),
          std::make_shared<HenonHeiles>(0.3, 2.0)};
}

TEST(Systems, VectorFieldIsJTimesGradientOfH) {
  std::mt19937_64 rng(11);
  for (const auto& system : all_systems()) {
    const Batch x = system->sample_initial_states(5, rng);
    Batch exact;
    system->vector_field(x, exact);
    const Batch fd = testing::symplectic_gradient_fd(*system, x);
    ASSERT_EQ(exact.rows(), 5);
    ASSERT_EQ(exact.cols(), system->dim());
    const double scale = std::max(1.0, exact.cwiseAbs().maxCoeff());
    EXPECT_LT((exact - fd).cwiseAbs().maxCoeff() / scale, 1e-7) << system->name();
  }
}

TEST(Systems, FieldCallableChecksTheStateWidth) {
  const Spring spring;
  const VectorField f = spring.field();
  Batch x(3, 2), dx(3, 2);
  x << 1, 0, 0, 1, 0.5, 0.5;
  f(0.0, x, dx);
  EXPECT_DOUBLE_EQ(dx(0, 1), -2.0);  // dp/dt = -2q
  EXPECT_DOUBLE_EQ(dx(1, 0), 2.0);   // dq/dt = 2p
  Batch wrong(3, 4), dwrong(3, 4);
  EXPECT_THROW(f(0.0, wrong, dwrong), std::invalid_argument);
}

TEST(Systems, EnergyAndHamiltonianAgreeOnSingleStatesAndBatches) {
  const Pendulum pendulum;
  Batch x(2, 2);
  x << 0.5, 1.0, -1.0, 0.25;
  const Eigen::VectorXd h = pendulum.hamiltonian_batch(x);
  EXPECT_DOUBLE_EQ(h(0), 3.0 * (1.0 - std::cos(0.5)) + 1.0);
  EXPECT_DOUBLE_EQ(pendulum.hamiltonian(x.row(1)), h(1));
  EXPECT_DOUBLE_EQ(pendulum.energy(x.row(1)), h(1));
  EXPECT_DOUBLE_EQ(Pendulum(2.4).hamiltonian(x.row(0)), 2.4 * (1.0 - std::cos(0.5)) + 1.0);
}

TEST(Systems, BadConstantsAreRejected) {
  EXPECT_THROW(Spring(-1.0), std::invalid_argument);
  EXPECT_THROW(Pendulum(0.0), std::invalid_argument);
  EXPECT_THROW(NBody({1.0}), std::invalid_argument);
  EXPECT_THROW(NBody({1.0, -1.0}), std::invalid_argument);
  EXPECT_THROW(NBody({1.0, 1.0}, 0.0), std::invalid_argument);
  EXPECT_THROW(DoublePendulum(1.0, 1.0, 0.0), std::invalid_argument);
  std::mt19937_64 rng(1);
  EXPECT_THROW(NBody::equal_masses(4).sample_initial_states(1, rng), std::logic_error);
}

TEST(SpringSampler, RadiiInRangeAndDirectionsSpread) {
  std::mt19937_64 rng(3);
  const Batch x = Spring().sample_initial_states(2000, rng);
  const Eigen::ArrayXd r = x.rowwise().norm().array();
  EXPECT_GE(r.minCoeff(), 0.1);
  EXPECT_LE(r.maxCoeff(), 1.0);
  EXPECT_NEAR(r.mean(), 0.55, 0.02);  // U[0.1, 1.0]
  // Every quadrant is visited (the direction is not degenerate).
  for (int sq : {1, -1}) {
    for (int sp : {1, -1}) {
      EXPECT_GT(((x.col(0).array() * sq > 0) && (x.col(1).array() * sp > 0)).count(), 300);
    }
  }
}

TEST(PendulumSampler, RadiiInRange) {
  std::mt19937_64 rng(4);
  const Eigen::ArrayXd r = Pendulum().sample_initial_states(2000, rng).rowwise().norm().array();
  EXPECT_GE(r.minCoeff(), 1.3);
  EXPECT_LE(r.maxCoeff(), 2.3);
  EXPECT_NEAR(r.mean(), 1.8, 0.03);
}

TEST(Samplers, SameSeedSameStates) {
  std::mt19937_64 a(99), b(99);
  const NBody three = NBody::equal_masses(3);
  EXPECT_EQ(three.sample_initial_states(7, a), three.sample_initial_states(7, b));
}

TEST(EvaluationSampler, ComponentsArePushedAwayFromZero) {
  std::mt19937_64 rng(5);
  const Batch x = sample_evaluation_states(15, rng);
  ASSERT_EQ(x.rows(), 15);
  ASSERT_EQ(x.cols(), 2);
  const Batch many = sample_evaluation_states(4000, rng);
  EXPECT_GE(many.cwiseAbs().minCoeff(), 0.2);
  EXPECT_LE(many.cwiseAbs().maxCoeff(), 1.0);
  EXPECT_NEAR(many.cwiseAbs().mean(), 0.6, 0.01);
}

TEST(Spring, ExactFlowIsTheClosedForm) {
  const Spring spring;  // dq/dt = 2p, dp/dt = -2q
  Batch x0(1, 2);
  x0 << 0.3, -0.7;
  const double t = 1.234;
  const Batch x = *spring.exact_flow(x0, t);
  EXPECT_NEAR(x(0, 0), 0.3 * std::cos(2 * t) - 0.7 * std::sin(2 * t), 1e-15);
  EXPECT_NEAR(x(0, 1), -0.7 * std::cos(2 * t) - 0.3 * std::sin(2 * t), 1e-15);
  EXPECT_DOUBLE_EQ(spring.omega(), 2.0);
  EXPECT_FALSE(Pendulum().exact_flow(x0, t).has_value());
}

TEST(TwoBodySampler, FollowsTasksMd) {
  const NBody two = NBody::equal_masses(2);
  std::mt19937_64 rng(6);
  const Batch x = two.sample_initial_states(500, rng);
  ASSERT_EQ(x.cols(), 8);
  EXPECT_LT(two.total_momentum(x).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT(two.center_of_mass(x).cwiseAbs().maxCoeff(), 1e-15);
  double mean_ratio = 0.0;
  for (int k = 0; k < x.rows(); ++k) {
    const Eigen::Vector2d pos(x(k, 0), x(k, 2)), vel(x(k, 4), x(k, 6));
    EXPECT_GE(pos.minCoeff(), 0.5);
    EXPECT_LE(pos.maxCoeff(), 1.5);
    EXPECT_NEAR(pos.dot(vel), 0.0, 1e-14);  // tangential
    const double circular = 1.0 / (2.0 * std::sqrt(pos.norm()));
    mean_ratio += vel.norm() / circular / x.rows();
    EXPECT_NEAR(vel.norm() / circular, 1.0, 0.05 * 5);  // (1 + 0.05 n), |n| < 5
  }
  EXPECT_NEAR(mean_ratio, 1.0, 0.01);
}

TEST(ThreeBodySampler, FollowsTasksMd) {
  const NBody three = NBody::equal_masses(3);
  std::mt19937_64 rng(7);
  const Batch x = three.sample_initial_states(300, rng);
  ASSERT_EQ(x.cols(), 12);
  const double speed =
      std::sqrt(std::sin(std::numbers::pi / 3) / (2 * std::pow(std::cos(std::numbers::pi / 6), 2)));
  for (int k = 0; k < x.rows(); ++k) {
    const Eigen::Vector2d p1(x(k, 0), x(k, 3)), p2(x(k, 1), x(k, 4)), p3(x(k, 2), x(k, 5));
    const double r = p1.norm();
    EXPECT_GE(r, 0.9);
    EXPECT_LE(r, 1.2);
    EXPECT_NEAR(p2.norm(), r, 1e-14);
    EXPECT_NEAR(p1.dot(p2), r * r * std::cos(2 * std::numbers::pi / 3), 1e-14);  // 120 degrees
    EXPECT_LT((p1 + p2 + p3).norm(), 1e-14);
    for (int b = 0; b < 3; ++b) {
      const Eigen::Vector2d pos(x(k, b), x(k, 3 + b)), vel(x(k, 6 + b), x(k, 9 + b));
      const Eigen::Vector2d nominal = Eigen::Vector2d(-pos.y(), pos.x()) / std::pow(r, 1.5) * speed;
      for (int axis = 0; axis < 2; ++axis) {
        if (std::abs(nominal(axis)) < 1e-9) continue;
        const double factor = vel(axis) / nominal(axis);
        EXPECT_GE(factor, 0.8 - 1e-12);
        EXPECT_LE(factor, 1.2 + 1e-12);
      }
    }
  }
}

TEST(NBody, ConservedQuantitiesByHand) {
  const NBody two(std::vector<double>{1.0, 3.0}, 2.0);
  Batch x(1, 8);
  // q1 = (1, 0), q2 = (-1, 0), p1 = (0, 2), p2 = (0, -1).
  x << 1, -1, 0, 0, 0, 0, 2, -1;
  EXPECT_DOUBLE_EQ(two.hamiltonian(x.row(0)), 4.0 / 2.0 + 1.0 / 6.0 - 2.0 * 3.0 / 2.0);
  EXPECT_DOUBLE_EQ(two.total_momentum(x)(0, 1), 1.0);
  EXPECT_DOUBLE_EQ(two.angular_momentum(x)(0), 1.0 * 2.0 + (-1.0) * (-1.0));
  EXPECT_DOUBLE_EQ(two.center_of_mass(x)(0, 0), (1.0 - 3.0) / 4.0);
  EXPECT_EQ(two.column(1, 1, true), 7);
  EXPECT_EQ(two.name(), "2body");
}

TEST(DoublePendulum, VelocityMomentumRoundTripAndKineticEnergy) {
  const DoublePendulum dp(1.2, 0.8, 0.9, 1.1, 9.81);
  Batch v(3, 4);
  v << 0.3, -0.4, 1.5, -2.0, 2.0, 1.0, 0.1, 0.2, -1.0, 0.5, -0.7, 1.3;
  const Batch x = dp.momenta_from_velocities(v);
  EXPECT_LT((dp.velocities_from_momenta(x) - v).cwiseAbs().maxCoeff(), 1e-13);
  // T from the Lagrangian in velocities must equal H - V.
  for (int k = 0; k < 3; ++k) {
    const double d = v(k, 0) - v(k, 1), w1 = v(k, 2), w2 = v(k, 3);
    const double kinetic = 0.5 * (1.2 + 0.8) * 0.81 * w1 * w1 + 0.5 * 0.8 * 1.21 * w2 * w2 +
                           0.8 * 0.9 * 1.1 * w1 * w2 * std::cos(d);
    const double potential =
        2.0 * 9.81 * 0.9 * (1 - std::cos(v(k, 0))) + 0.8 * 9.81 * 1.1 * (1 - std::cos(v(k, 1)));
    EXPECT_NEAR(dp.hamiltonian(x.row(k)), kinetic + potential, 1e-12);
  }
}

// The pendulum in velocities must move exactly as the canonical one: integrate both from the same
// states (converted) and compare; its energy must be the canonical H and stay constant.
TEST(DoublePendulumVelocities, MovesAsTheCanonicalSystemAndConservesEnergy) {
  const DoublePendulumVelocities lagrangian(1.2, 0.8, 0.9, 1.1, 9.8);
  const DoublePendulum& canonical = lagrangian.canonical();
  Batch v0(3, 4);
  v0 << 0.3, -0.4, 1.5, -2.0, 2.0, 1.0, 0.1, 0.2, -1.0, 2.5, -0.7, 1.3;
  const auto dopri = make_integrator("dopri5", {.rtol = 1e-12, .atol = 1e-13});
  const std::vector<double> t = linspace(0.0, 3.0, 4);
  const Trajectory in_velocities = dopri->integrate(lagrangian.field(), v0, t);
  const Trajectory in_momenta =
      dopri->integrate(canonical.field(), canonical.momenta_from_velocities(v0), t);
  for (std::size_t k = 0; k < t.size(); ++k) {
    const Batch converted = canonical.velocities_from_momenta(in_momenta.states[k]);
    EXPECT_LT((in_velocities.states[k] - converted).cwiseAbs().maxCoeff(), 1e-8) << "t = " << t[k];
    EXPECT_LT((lagrangian.hamiltonian_batch(in_velocities.states[k]) -
               canonical.hamiltonian_batch(in_momenta.states[k]))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-9);
  }
  EXPECT_LT(
      (lagrangian.hamiltonian_batch(in_velocities.states.back()) - lagrangian.hamiltonian_batch(v0))
          .cwiseAbs()
          .maxCoeff(),
      1e-9);
}

}  // namespace
}  // namespace hnn::physics
