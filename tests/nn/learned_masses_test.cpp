// Learned masses (nn/constrained/masses.h): the inverse mass matrix of point masses and rigid
// bodies as a positive sum over its bodies' basis, refused for any other mass matrix; a CHNN or
// CLNN whose learned masses sit at the true ones moves exactly as one given them; and the
// training loss differentiates to second order in the log masses too.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "constrained_test_util.h"
#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::chain_spec;
using nn::testing::constrained_config;

namespace learned_masses_test {

// A rigid body in 3-D as Finzi et al. build one: a centre (point 0) and one point on each
// principal axis, M = [[m + sum I, -I_j], [-I_j, diag I_j]]; six links keep it rigid and its
// centre is pinned.
const double kBodyMass = 1.7;
const Eigen::Vector3d kMoments{0.4, 0.9, 1.3};

nn::ConstraintSpec rigid_body() {
  nn::ConstraintSpec spec;
  spec.points = 4;
  spec.dim = 3;
  spec.mass = Eigen::MatrixXd::Zero(4, 4);
  spec.mass(0, 0) = kBodyMass + kMoments.sum();
  for (int j = 1; j <= 3; ++j) {
    spec.mass(j, j) = kMoments[j - 1];
    spec.mass(0, j) = spec.mass(j, 0) = -kMoments[j - 1];
  }
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) spec.links.push_back({i, j, i == 0 ? 1.0 : std::sqrt(2.0)});
  spec.pins.push_back({{1.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}});
  return spec;
}

// States near the body's rest shape (centre at the origin, axis points on the unit vectors).
MatrixD body_states(Eigen::Index rows, std::mt19937_64& rng) {
  MatrixD z = 0.05 * nn::random_uniform<double>(rows, 24, rng, -1, 1);
  for (int j = 1; j <= 3; ++j) z.col(3 * j + j - 1).array() += 1.0;
  return z;
}

nn::ConstraintSpec learned(nn::ConstraintSpec spec) {
  spec.learned_masses = true;
  return spec;
}

// A model with learned masses whose MLP is `known`'s and whose log masses are the true ones.
nn::ConstrainedModel<double> at_true_masses(const nn::ConstrainedModel<double>& known) {
  nn::DynamicsConfig config = known.config();
  config.constraints.learned_masses = true;
  const Eigen::RowVectorXd log_masses =
      -nn::inverse_mass_coefficients(config.constraints).array().log().transpose();
  return nn::ConstrainedModel<double>(config, known.mlp().cast<double>(), log_masses);
}

}  // namespace learned_masses_test

using namespace learned_masses_test;

TEST(LearnedMasses, PointMassesAndARigidBodyAreSumsOfTheirBasis) {
  const nn::ConstraintSpec chain =
      chain_spec({1.0, 0.8}, 2, Eigen::Vector2d(2.0, 0.5).asDiagonal(), {0, 0});
  EXPECT_TRUE(nn::inverse_mass_coefficients(chain).isApprox(Eigen::Vector2d(0.5, 2.0)));
  const Eigen::Vector4d body = nn::inverse_mass_coefficients(rigid_body());
  EXPECT_NEAR(body[0], 1 / kBodyMass, 1e-12);
  for (int j = 1; j <= 3; ++j) EXPECT_NEAR(body[j], 1 / kMoments[j - 1], 1e-12);
  const std::vector<Eigen::MatrixXd> basis = nn::inverse_mass_basis(rigid_body());
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(4, 4);
  for (int k = 0; k < 4; ++k) sum += body[k] * basis[std::size_t(k)];
  EXPECT_LT((sum * rigid_body().mass - Eigen::MatrixXd::Identity(4, 4)).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST(LearnedMasses, AMassMatrixOfNeitherPointMassesNorRigidBodiesIsRefused) {
  Eigen::MatrixXd coupled(2, 2);  // two points coupled, but not as a rigid body's centre and axis
  coupled << 1.5, 0.3, 0.3, 0.8;
  const nn::ConstraintSpec spec = learned(chain_spec({1.0, 0.8}, 2, coupled, {0, 0}));
  const std::string message =
      nn::testing::message_of<std::invalid_argument>([&] { nn::inverse_mass_coefficients(spec); });
  EXPECT_NE(message.find("learned masses: the mass matrix's inverse is not a positive sum"),
            std::string::npos)
      << message;
  EXPECT_THROW(nn::ConstrainedMechanics<double>{spec}, std::invalid_argument);
}

TEST(LearnedMasses, AtTheTrueMassesTheFieldAndEnergyAreTheKnownModels) {
  const nn::ConstraintSpec chain =
      chain_spec({1.0, 0.8, 1.2}, 2, Eigen::Vector3d(0.7, 1.3, 1.1).asDiagonal(), {0.1, 0});
  for (const nn::ConstraintSpec& spec : {chain, rigid_body()}) {
    for (ModelKind kind : {ModelKind::kChnn, ModelKind::kClnn}) {
      std::mt19937_64 rng(41);
      const nn::ConstrainedModel<double> known(constrained_config(kind, spec, {8, 8}), rng);
      const nn::ConstrainedModel<double> learned = at_true_masses(known);
      const MatrixD z =
          spec.pins.empty() ? nn::testing::chain_states(spec, 5, 42) : body_states(5, rng);
      const MatrixD want = known.field(z), got = learned.field(z);
      EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 1e-12 * want.cwiseAbs().maxCoeff())
          << nn::to_string(kind) << ", " << spec.points << " points";
      EXPECT_LT((learned.energy(z) - known.energy(z)).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_TRUE(learned.inverse_mass_coefficients().transpose().isApprox(
          nn::inverse_mass_coefficients(spec)));
    }
  }
}

TEST(LearnedMasses, TrainingGradientsReachTheLogMassesToSecondOrder) {
  for (const nn::ConstraintSpec& spec :
       {learned(chain_spec({1.0, 0.8}, 2, Eigen::Vector2d(0.9, 1.2).asDiagonal(), {0, 0})),
        learned(rigid_body())}) {
    for (ModelKind kind : {ModelKind::kChnn, ModelKind::kClnn}) {
      std::mt19937_64 rng(43);
      const nn::ConstrainedModel<double> model(constrained_config(kind, spec, {4, 3}), rng);
      ASSERT_EQ(model.named_parameters().back().name, "log_masses");
      const MatrixD z =
          spec.pins.empty() ? nn::testing::chain_states(spec, 3, 44) : body_states(3, rng);
      const MatrixD target = nn::random_uniform<double>(3, z.cols(), rng, -1, 1);
      const auto checks = nn::testing::check_training_gradients(model, z, target);
      EXPECT_TRUE(checks.first.ok) << nn::to_string(kind) << ": " << checks.first.log;
      EXPECT_TRUE(checks.second.ok) << nn::to_string(kind) << ": " << checks.second.log;
    }
  }
}

TEST(LearnedMasses, DrawnNearOneCastAndDescribed) {
  const nn::ConstraintSpec spec = learned(rigid_body());
  std::mt19937_64 rng(45);
  const nn::ConstrainedModel<double> model(constrained_config(ModelKind::kChnn, spec, {4}), rng);
  const MatrixD c = model.inverse_mass_coefficients();
  ASSERT_EQ(c.cols(), 4);
  EXPECT_GT(c.minCoeff(), std::exp(-0.5));  // 0.1 N(0, 1) log masses: within 5 sigma of 1
  EXPECT_LT(c.maxCoeff(), std::exp(0.5));
  EXPECT_FALSE(c.isApprox(MatrixD::Ones(1, 4)));
  const nn::ConstrainedModel<float> single = model.cast<float>();
  EXPECT_TRUE(single.inverse_mass_coefficients().cast<double>().isApprox(c, 1e-6));
  EXPECT_NE(model.describe().find("learned masses"), std::string::npos) << model.describe();
}

// tangent_mass_error compares masses only where the motion can tell them apart: on the tangent
// space of the constraints, up to one scale. A body pinned at its centre moves alike whatever its
// mass (its inertia about the pin is its moments' alone); a chain's masses all count.
TEST(LearnedMasses, TheTangentMassErrorSeesOnlyWhatMovesTheSystem) {
  const nn::ConstraintSpec chain =
      chain_spec({1.0, 0.8, 1.2}, 2, Eigen::Vector3d(0.7, 1.3, 1.1).asDiagonal(), {0.1, 0});
  const MatrixD chain_x = nn::testing::chain_states(chain, 6, 46).leftCols(6);
  const Eigen::VectorXd c = nn::inverse_mass_coefficients(chain);
  const nn::ConstrainedMechanics<double> chain_mechanics(learned(chain));
  // The error of coefficients c against the system's own masses at the states x.
  const auto error = [](const nn::ConstrainedMechanics<double>& mechanics,
                        const Eigen::VectorXd& coefficients, const MatrixD& x) {
    return nn::tangent_mass_error(mechanics.spec(), mechanics.mass_matrix(coefficients.transpose()),
                                  mechanics.mass(), x);
  };
  EXPECT_LT(error(chain_mechanics, c, chain_x), 1e-12);
  EXPECT_LT(error(chain_mechanics, 3.0 * c, chain_x), 1e-12);
  Eigen::VectorXd heavier = c;
  heavier[1] *= 1.5;
  EXPECT_GT(error(chain_mechanics, heavier, chain_x), 0.01);

  const nn::ConstrainedMechanics<double> body(learned(rigid_body()));
  MatrixD body_x(5, 12);  // rotations of the rest shape: centre at the pin, axis points on R e_j
  std::mt19937_64 rng(47);
  for (Eigen::Index r = 0; r < body_x.rows(); ++r) {
    const Eigen::Vector3d axis = nn::random_normal<double>(3, 1, rng).col(0).normalized();
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(1.0 + double(r), axis).toRotationMatrix();
    body_x.row(r) << 0, 0, 0, rotation.col(0).transpose(), rotation.col(1).transpose(),
        rotation.col(2).transpose();
  }
  const Eigen::VectorXd b = nn::inverse_mass_coefficients(body.spec());
  Eigen::VectorXd other_mass = b, other_moment = b;
  other_mass[0] *= 5.0;    // 1 / m
  other_moment[2] *= 1.5;  // 1 / I_y
  EXPECT_LT(error(body, other_mass, body_x), 1e-12);
  EXPECT_GT(error(body, other_moment, body_x), 0.01);
  EXPECT_THROW(error(body, b.head(3), body_x), std::invalid_argument);
}
