// The mass HNN (Finzi et al.'s HNN, nn/mass_hnn.h): its field in (q, v) is Hamilton's equations
// of its own H(q, p) = 1/2 p^T M^-1(q) p + V(q) with p = M(q) v, checked against central
// differences of H and of v = M^-1 p; it conserves its learned energy; its M^-1 is positive
// definite; the (q, p) it carries through integrators is the same motion; its training
// gradients, in (q, v) and through a carried step, match finite differences to second order;
// float and double casts agree; a clear error for what it cannot be.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::small_config;

namespace {

constexpr double kStep = 1e-5;  // central differences: error ~ kStep^2 of the third derivatives

MatrixD random_qv(Eigen::Index rows, Eigen::Index dim, std::uint64_t seed, double scale = 1) {
  std::mt19937_64 rng(seed);
  return nn::random_uniform<double>(rows, dim, rng, -scale, scale);
}

nn::MassHnn<double> small_mass_hnn(Eigen::Index dim, Eigen::Index angles, std::uint64_t seed,
                                   std::vector<Eigen::Index> hidden = {12, 10}) {
  std::mt19937_64 rng(seed);
  nn::DynamicsConfig config = small_config(ModelKind::kMassHnn, dim, std::move(hidden));
  config.angles = angles;
  return nn::MassHnn<double>(config, rng);
}

// Row r's n x n block of a batch of flattened blocks.
Eigen::MatrixXd block_of(const MatrixD& blocks, Eigen::Index r, Eigen::Index n) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      blocks.row(r).data(), n, n);
}

// The state (q, M^-1(q) p) of positions q and momenta p: the model's H(q, p) is its energy there.
MatrixD state_of(const nn::MassHnn<double>& model, const MatrixD& q, const MatrixD& p) {
  const Eigen::Index n = q.cols();
  MatrixD x(q.rows(), 2 * n);
  x << q, MatrixD::Zero(q.rows(), n);
  const MatrixD minv = model.inverse_mass(x);
  for (Eigen::Index r = 0; r < q.rows(); ++r)
    x.row(r).rightCols(n) = (block_of(minv, r, n) * p.row(r).transpose()).transpose();
  return x;
}

// p = M(q) v of each row.
MatrixD momenta(const nn::MassHnn<double>& model, const MatrixD& x) {
  const Eigen::Index n = x.cols() / 2;
  const MatrixD minv = model.inverse_mass(x);
  MatrixD p(x.rows(), n);
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    p.row(r) = block_of(minv, r, n).llt().solve(x.row(r).rightCols(n).transpose()).transpose();
  return p;
}

void expect_hamiltons_equations(const nn::MassHnn<double>& model, const MatrixD& x) {
  const Eigen::Index n = x.cols() / 2;
  const MatrixD f = model.field(x), q = x.leftCols(n), p = momenta(model, x);
  EXPECT_EQ(f.leftCols(n), x.rightCols(n)) << "dq/dt is v";
  // dp/dt = -dH/dq at fixed p, by central differences of H(q, p) = energy(q, M^-1(q) p).
  MatrixD p_dot(x.rows(), n);
  for (Eigen::Index i = 0; i < n; ++i) {
    MatrixD up = q, down = q;
    up.col(i).array() += kStep;
    down.col(i).array() -= kStep;
    p_dot.col(i) =
        -(model.energy(state_of(model, up, p)) - model.energy(state_of(model, down, p))) /
        (2 * kStep);
  }
  // dv/dt = d/dt (M^-1(q) p) along (dq/dt, dp/dt), by central differences.
  const MatrixD ahead = state_of(model, q + kStep * f.leftCols(n), p + kStep * p_dot);
  const MatrixD behind = state_of(model, q - kStep * f.leftCols(n), p - kStep * p_dot);
  const MatrixD v_dot = (ahead.rightCols(n) - behind.rightCols(n)) / (2 * kStep);
  EXPECT_LT((f.rightCols(n) - v_dot).cwiseAbs().maxCoeff(),
            1e-7 * (1 + v_dot.cwiseAbs().maxCoeff()))
      << "field dv/dt\n"
      << f.rightCols(n) << "\nby differences\n"
      << v_dot;
  // The learned energy is constant along the learned motion.
  const MatrixD e_dot = (model.energy(x + kStep * f) - model.energy(x - kStep * f)) / (2 * kStep);
  EXPECT_LT(e_dot.cwiseAbs().maxCoeff(), 1e-7 * (1 + f.cwiseAbs().maxCoeff()));
}

}  // namespace

TEST(MassHnn, FieldIsHamiltonsEquationsOfItsLearnedEnergy) {
  for (const Eigen::Index n : {1, 2, 3}) {
    SCOPED_TRACE(testing::Message() << n << " coordinates, all angles");
    const nn::MassHnn<double> model = small_mass_hnn(2 * n, n, 30 + std::uint64_t(n));
    expect_hamiltons_equations(model, random_qv(5, 2 * n, 40 + std::uint64_t(n), 2.0));
  }
  SCOPED_TRACE("2 coordinates, no angles, scaled inputs");
  std::mt19937_64 rng(50);
  nn::DynamicsConfig config = small_config(ModelKind::kMassHnn, 4, {9, 7});
  config.input_scale = {2.0, 0.5, 1.0, 1.0};
  expect_hamiltons_equations(nn::MassHnn<double>(config, rng), random_qv(4, 4, 51));
}

TEST(MassHnn, LearnedInverseMassIsSymmetricPositiveDefinite) {
  const nn::MassHnn<double> model = small_mass_hnn(6, 3, 60);
  const MatrixD x = random_qv(20, 6, 61, 10.0);
  const MatrixD minv = model.inverse_mass(x);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::MatrixXd m = block_of(minv, r, 3);
    EXPECT_LT((m - m.transpose()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m).eigenvalues().minCoeff(),
              nn::kMassHnnEpsilon * (1 - 1e-9));
  }
}

TEST(MassHnn, TrainingGradientsMatchFiniteDifferencesToSecondOrder) {
  const nn::MassHnn<double> model = small_mass_hnn(4, 2, 70, {5, 4});
  const auto checks =
      nn::testing::check_training_gradients(model, random_qv(3, 4, 71), random_qv(3, 4, 72));
  EXPECT_TRUE(checks.first.ok) << checks.first.worst << "\n" << checks.first.log;
  EXPECT_TRUE(checks.second.ok) << checks.second.worst << "\n" << checks.second.log;
}

// Fixed-step integrators carry (q, p) (nn/mass_hnn.h): the map there and back is the identity,
// its p is M(q) v, and the carried field, seen through observed_state, is time_derivative's
// motion in (q, v).
TEST(MassHnn, CarriesCanonicalStatesForIntegrators) {
  const nn::MassHnn<double> model = small_mass_hnn(6, 3, 100);
  const MatrixD x = random_qv(5, 6, 101, 2.0);
  const auto state = [&](const MatrixD& z) {
    return model.observed_state(Var<double>::constant(z)).value();
  };
  const MatrixD z = model.integrated_state(Var<double>::constant(x)).value();
  EXPECT_EQ(z.leftCols(3), x.leftCols(3));
  EXPECT_LT((z.rightCols(3) - momenta(model, x)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((state(z) - x).cwiseAbs().maxCoeff(), 1e-12);
  const MatrixD g = model.integrated_derivative(Var<double>::constant(z)).value();
  const MatrixD along = (state(z + kStep * g) - state(z - kStep * g)) / (2 * kStep);
  const MatrixD f = model.field(x);
  EXPECT_LT((along - f).cwiseAbs().maxCoeff(), 1e-7 * (1 + f.cwiseAbs().maxCoeff()))
      << "d/dt observed_state along the carried field\n"
      << along << "\ntime_derivative\n"
      << f;
}

TEST(MassHnn, CarriedStepGradientsMatchFiniteDifferencesToSecondOrder) {
  const nn::MassHnn<double> model = small_mass_hnn(4, 2, 110, {5, 4});
  // One explicit Euler step in (q, p), read back in (q, v): every carried piece on one path.
  const auto step = [&](const Var<double>& x) {
    const Var<double> z = model.integrated_state(x);
    return model.observed_state(z + model.integrated_derivative(z) * 0.1);
  };
  const auto checks = nn::testing::check_training_gradients(model, random_qv(3, 4, 111),
                                                            random_qv(3, 4, 112), step);
  EXPECT_TRUE(checks.first.ok) << checks.first.worst << "\n" << checks.first.log;
  EXPECT_TRUE(checks.second.ok) << checks.second.worst << "\n" << checks.second.log;
}

TEST(MassHnn, HasBothNetworksAsParametersAndCastsToFloat) {
  const nn::MassHnn<double> model = small_mass_hnn(4, 2, 80);
  std::vector<std::string> names;
  for (const auto& p : model.named_parameters()) names.push_back(p.name);
  EXPECT_EQ(names.front(), "mlp.layers.0.weight");
  EXPECT_EQ(names.back(), "mass.layers.2.bias");
  EXPECT_EQ(model.factor_mlp().layers().back().bias().value(), MatrixD::Zero(1, 4))
      << "the factor's last bias starts at zero, as theirs";
  EXPECT_EQ(model.kind(), "hnn-mass:tanh");
  EXPECT_EQ(model.describe(), "hnn-mass V 4-12-10-1, L 4-12-10-4 tanh orthogonal");
  const auto single = nn::cast_model<float>(model);
  const MatrixD x = random_qv(6, 4, 81);
  const MatrixD f = single->field(x.cast<float>()).cast<double>();
  EXPECT_LT((f - model.field(x)).cwiseAbs().maxCoeff(), 1e-4 * (1 + f.cwiseAbs().maxCoeff()));
}

TEST(MassHnn, RefusesWhatItCannotBe) {
  std::mt19937_64 rng(90);
  nn::DynamicsConfig odd = small_config(ModelKind::kMassHnn, 3, {4});
  EXPECT_THROW(
      {
        try {
          nn::MassHnn<double> model(odd, rng);
        } catch (const std::invalid_argument& e) {
          EXPECT_STREQ(e.what(),
                       "model: an hnn-mass needs an even state dimension x = (q, v), got 3");
          throw;
        }
      },
      std::invalid_argument);
  nn::DynamicsConfig relu = small_config(ModelKind::kMassHnn, 4, {4});
  relu.activation = nn::Activation::kRelu;
  EXPECT_THROW(nn::MassHnn<double>(relu, rng), std::invalid_argument);
  EXPECT_THROW(nn::MassHnn<double>(small_config(ModelKind::kLnn, 4, {4}), rng),
               std::invalid_argument);
}
