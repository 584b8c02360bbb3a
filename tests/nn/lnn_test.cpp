// The Lagrangian NN: its acceleration against per-row Hessians solved by Eigen, its training
// gradient against finite differences (a third-order path, checked to second order), its learned
// energy conserved along its own flow, periodic angles, and a clear error where the learned L has
// no motion (a singular d²L/dv²).

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <numbers>

#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::small_config;

namespace {

MatrixD random_states(Eigen::Index rows, Eigen::Index dim, std::uint64_t seed, double scale = 1) {
  std::mt19937_64 rng(seed);
  return nn::random_uniform<double>(rows, dim, rng, -scale, scale);
}

// A small LNN, with the default kinetic prior or (kinetic_prior 0) the plain L = MLP of Cranmer
// et al.: a small random MLP alone can be indefinite, so tests of it pick seeds and states where
// the solve is well posed.
nn::Lnn<double> small_lnn(Eigen::Index dim, std::uint64_t seed,
                          nn::Activation act = nn::Activation::kTanh, double kinetic_prior = 1.0) {
  std::mt19937_64 rng(seed);
  nn::DynamicsConfig config =
      small_config(ModelKind::kLnn, dim, {12, 12}, nn::FieldType::kSolenoidal, act);
  config.kinetic_prior = kinetic_prior;
  return nn::Lnn<double>(config, rng);
}

// The acceleration of row r by hand: ad::hessian of L at that row alone, solved by Eigen.
Eigen::VectorXd acceleration_by_hand(const nn::Lnn<double>& lnn, const MatrixD& x, Eigen::Index r) {
  const Eigen::Index n = x.cols() / 2;
  const MatrixD row = x.row(r);
  const ad::VarFunction<double> l = [&](const Var<double>& v) {
    return ad::sum(lnn.lagrangian(v));
  };
  const MatrixD h = ad::hessian<double>(l, row);
  const MatrixD g = ad::jacobian<double>(l, row);  // 1 x 2n
  const MatrixD hvv = h.bottomRightCorner(n, n), hvq = h.bottomLeftCorner(n, n);
  const Eigen::VectorXd v = row.rightCols(n).transpose();
  const Eigen::VectorXd rhs = g.leftCols(n).transpose() - hvq * v;
  return hvv.partialPivLu().solve(rhs);
}

// The training loss's gradients against finite differences, with and without an angle (the
// chain rule through its cos and sin).
void expect_training_gradients_match(Eigen::Index angles) {
  const nn::Lnn<double> lnn = [&] {
    std::mt19937_64 rng(21);
    nn::DynamicsConfig config = small_config(ModelKind::kLnn, 2, {5, 4});
    config.angles = angles;
    return nn::Lnn<double>(config, rng);
  }();
  const auto checks =
      nn::testing::check_training_gradients(lnn, random_states(3, 2, 22), random_states(3, 2, 23));
  EXPECT_TRUE(checks.first.ok) << checks.first.worst << "\n" << checks.first.log;
  EXPECT_TRUE(checks.second.ok) << checks.second.worst << "\n" << checks.second.log;
}

}  // namespace

TEST(Lnn, AccelerationIsTheEulerLagrangeSolveOfEachRow) {
  for (const auto& [act, prior] : {std::pair{nn::Activation::kTanh, 1.0},
                                   {nn::Activation::kSoftplus, 1.0},
                                   {nn::Activation::kTanh, 0.0},
                                   {nn::Activation::kSoftplus, 0.0}}) {
    const nn::Lnn<double> lnn = small_lnn(4, 11, act, prior);
    const MatrixD x = random_states(6, 4, 12);
    const MatrixD f = lnn.field(x);
    ASSERT_EQ(f.rows(), 6);
    ASSERT_EQ(f.cols(), 4);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      EXPECT_EQ(f.row(r).leftCols(2), x.row(r).rightCols(2)) << "dq/dt is v";
      const Eigen::VectorXd a = acceleration_by_hand(lnn, x, r);
      EXPECT_LT((f.row(r).rightCols(2).transpose() - a).cwiseAbs().maxCoeff(),
                1e-9 * (1 + a.cwiseAbs().maxCoeff()))
          << nn::to_string(act) << ", prior " << prior << ", row " << r;
    }
    // The training path (recorded) gives the same values as the values-only one.
    ad::TapeScope scope;
    EXPECT_LT((lnn.time_derivative(Var<double>::constant(x)).value() - f).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

// The field of every model family is its formula in x itself when the MLP sees x / scale: the
// acceleration against the by-hand solve (ad::hessian of lagrangian(x)), and an HNN's field
// against the symplectic gradient of its energy(x).
TEST(Lnn, InputScalesLeaveTheEulerLagrangeEquationsOfLIntact) {
  std::mt19937_64 rng(71);
  nn::DynamicsConfig config = small_config(ModelKind::kLnn, 4, {12, 12});
  config.input_scale = {1.0, 2.0, 10.0, 5.0};
  const nn::Lnn<double> lnn(config, rng);
  const MatrixD x = random_states(4, 4, 72, 3.0);
  const MatrixD f = lnn.field(x);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::VectorXd a = acceleration_by_hand(lnn, x, r);
    EXPECT_LT((f.row(r).rightCols(2).transpose() - a).cwiseAbs().maxCoeff(),
              1e-9 * (1 + a.cwiseAbs().maxCoeff()))
        << "row " << r;
  }
  config.model = ModelKind::kHnn;
  const nn::Hnn<double> hnn(config, rng);
  ad::TapeScope scope;
  const Var<double> xv = Var<double>::leaf(x);
  const MatrixD dh = ad::grad<double>({ad::sum(hnn.energy(xv))}, {xv})[0].value();
  const MatrixD g = hnn.field(x);
  EXPECT_LT((g.leftCols(2) - dh.rightCols(2)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((g.rightCols(2) + dh.leftCols(2)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Lnn, TrainingLossMatchesFiniteDifferencesUpToSecondOrder) {
  for (const Eigen::Index angles : {0, 1}) expect_training_gradients_match(angles);
}

namespace {

void expect_energy_conserved(const nn::Lnn<double>& lnn, const MatrixD& x) {
  const MatrixD f = lnn.field(x);
  const double eps = 1e-5;
  const MatrixD along = (lnn.energy(x + eps * f) - lnn.energy(x - eps * f)) / (2 * eps);
  MatrixD other = f;
  other.col(0).swap(other.col(1));  // a direction that is not the flow
  const MatrixD across = (lnn.energy(x + eps * other) - lnn.energy(x - eps * other)) / (2 * eps);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const double scale = 1 + f.row(r).norm();
    EXPECT_LT(std::abs(along(r, 0)), 1e-7 * scale) << "row " << r;
    EXPECT_GT(std::abs(across(r, 0)), 1e-4) << "row " << r;
  }
}

}  // namespace

// dE/dt = dE/dx · f(x) = 0 at every state where the motion is defined (an identity of the
// Euler-Lagrange equations), checked by a central difference of E along f; and E against a
// moving state, to show the check has teeth.
TEST(Lnn, ConservesItsLearnedEnergyAlongItsOwnFlow) {
  for (const bool scaled : {false, true}) {
    std::mt19937_64 rng(31);
    nn::DynamicsConfig config = small_config(ModelKind::kLnn, 4, {12, 12});
    if (scaled) {  // as the double pendulum's: wrapped angles, velocities seen / 10
      config.angles = 2;
      config.input_scale = {1.0, 1.0, 10.0, 10.0};
    }
    expect_energy_conserved(nn::Lnn<double>(config, rng), random_states(8, 4, 32, scaled ? 5 : 1));
  }
}

TEST(Lnn, SeesAnglesAsPeriodic) {
  std::mt19937_64 rng(41);
  nn::DynamicsConfig config = small_config(ModelKind::kLnn, 4, {12});
  config.angles = 2;
  const nn::Lnn<double> lnn(config, rng);
  const MatrixD x = random_states(4, 4, 42);
  MatrixD shifted = x;
  shifted.col(0).array() += 2 * std::numbers::pi;
  shifted.col(1).array() -= 4 * std::numbers::pi;
  EXPECT_LT((lnn.field(x) - lnn.field(shifted)).cwiseAbs().maxCoeff(), 1e-9);
  // Smooth over the top: just before +pi and just after -pi are neighbours (a wrap to
  // [-pi, pi) would jump there).
  MatrixD below = x, above = x;
  below.col(0).setConstant(std::numbers::pi - 1e-7);
  above.col(0).setConstant(-std::numbers::pi + 1e-7);
  EXPECT_LT((lnn.field(below) - lnn.field(above)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((lnn.energy(below) - lnn.energy(above)).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Lnn, ASingularVelocityHessianIsAClearError) {
  nn::Lnn<double> lnn = small_lnn(4, 51, nn::Activation::kTanh, /*kinetic_prior=*/0.0);
  // L linear in v: d²L/dv² = 0 everywhere, so the motion is undefined.
  for (Var<double>& p : lnn.parameters()) p.mutable_value().setZero();
  const MatrixD x = random_states(5, 4, 52);
  try {
    (void)lnn.field(x);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
}

// With the MLP zeroed, L is the prior alone, |v / scale|² / 2: a free particle, which neither
// accelerates nor changes its energy |v / scale|² / 2.
TEST(Lnn, TheKineticPriorAloneIsAFreeParticle) {
  std::mt19937_64 rng(55);
  nn::DynamicsConfig config = small_config(ModelKind::kLnn, 4, {6});
  config.input_scale = {1.0, 1.0, 2.0, 4.0};
  config.kinetic_prior = 3.0;
  nn::Lnn<double> lnn(config, rng);
  for (Var<double>& p : lnn.parameters()) p.mutable_value().setZero();
  const MatrixD x = random_states(5, 4, 56, 2.0);
  const MatrixD f = lnn.field(x);
  EXPECT_EQ(f.leftCols(2), x.rightCols(2));
  EXPECT_LT(f.rightCols(2).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::VectorXd expected =
      1.5 * ((x.col(2) / 2.0).array().square() + (x.col(3) / 4.0).array().square()).matrix();
  EXPECT_LT((lnn.energy(x).col(0) - expected).cwiseAbs().maxCoeff(), 1e-12);
  config.kinetic_prior = -1;
  EXPECT_THROW(nn::Lnn<double>(config, rng), std::invalid_argument);
}

TEST(Lnn, CastsAndRefusesOtherConfigs) {
  const nn::Lnn<double> lnn = small_lnn(4, 61);
  const MatrixD x = random_states(3, 4, 62);
  const auto as_float = nn::cast_model<float>(lnn);
  EXPECT_EQ(as_float->name(), "lnn");
  EXPECT_LT((as_float->field(x.cast<float>()).cast<double>() - lnn.field(x)).cwiseAbs().maxCoeff(),
            1e-2);
  std::mt19937_64 rng(63);
  EXPECT_THROW(nn::Lnn<double>(small_config(ModelKind::kHnn, 4, {4}), rng), std::invalid_argument);
  EXPECT_THROW(nn::Hnn<double>(small_config(ModelKind::kLnn, 4, {4}), rng), std::invalid_argument);
  EXPECT_THROW(nn::Lnn<double>(small_config(ModelKind::kLnn, 3, {4}), rng), std::invalid_argument);
  EXPECT_EQ(nn::make_model<double>(small_config(ModelKind::kLnn, 4, {4}), rng)->name(), "lnn");
}
