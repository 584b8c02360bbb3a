// The CHNN and CLNN as trainable models: their training loss differentiated to second order in
// the states and the parameters (the rollout loss differentiates the field in the state), a tiny
// training run on a 1-link Cartesian pendulum, the factory, casts and checkpoint names, and the
// config checks that refuse a system a model cannot take.

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "constrained_test_util.h"
#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::chain_spec;
using nn::testing::constrained_config;

namespace constrained_training_test {

// A 2-link chain in 2-D with a non-diagonal mass matrix.
nn::ConstraintSpec double_chain() {
  Eigen::MatrixXd mass(2, 2);
  mass << 1.5, 0.3, 0.3, 0.8;
  return chain_spec({1.0, 0.8}, 2, mass, {0.1, 0.2});
}

// Two points in 2-D on a link, a weighted point between them pinned (a ball joint), and states
// near it: x_0 near (-0.5, 0), x_1 near (0.5, 0).
nn::ConstraintSpec pinned_pair() {
  nn::ConstraintSpec spec = chain_spec({1.0, 1.0}, 2, Eigen::MatrixXd::Identity(2, 2), {0, 0});
  spec.anchors.clear();
  spec.pins.push_back({{0.6, 0.4}, {0.1, 0.0}});
  return spec;
}

MatrixD pinned_pair_states(std::mt19937_64& rng) {
  MatrixD z = 0.2 * nn::random_uniform<double>(2, 8, rng, -1, 1);
  z.col(0).array() -= 0.5;
  z.col(2).array() += 0.5;
  return z;
}

// The message of the std::invalid_argument that making a model from `config` throws.
std::string config_error(const nn::DynamicsConfig& config) {
  return nn::testing::message_of<std::invalid_argument>([&] {
    std::mt19937_64 rng(0);
    nn::make_model<double>(config, rng);
  });
}

}  // namespace constrained_training_test

using namespace constrained_training_test;

TEST(ConstrainedTraining, LossGradientsMatchFiniteDifferencesToSecondOrder) {
  const nn::ConstraintSpec spec = double_chain();
  for (ModelKind kind : {ModelKind::kChnn, ModelKind::kClnn}) {
    std::mt19937_64 rng(21);
    const nn::ConstrainedModel<double> model(constrained_config(kind, spec, {5, 4}), rng);
    // Slightly off the manifold, where the CHNN's position projection is not zero.
    const MatrixD z = nn::testing::chain_states(spec, 3, 22) +
                      0.05 * nn::random_uniform<double>(3, 8, rng, -1, 1);
    const MatrixD target = nn::random_uniform<double>(3, 8, rng, -1, 1);
    const auto checks = nn::testing::check_training_gradients(model, z, target);
    EXPECT_TRUE(checks.first.ok) << nn::to_string(kind) << ": " << checks.first.worst << "\n"
                                 << checks.first.log;
    EXPECT_TRUE(checks.second.ok) << nn::to_string(kind) << ": " << checks.second.worst << "\n"
                                  << checks.second.log;
  }
}

TEST(ConstrainedTraining, MechanicsDifferentiateInStateAndPotentialGradient) {
  for (const nn::ConstraintSpec& spec : {double_chain(), pinned_pair()}) {
    const nn::ConstrainedMechanics<double> mechanics(spec);
    std::mt19937_64 rng(23);
    const std::vector<MatrixD> inputs{
        spec.pins.empty() ? nn::testing::chain_states(spec, 2, 24) : pinned_pair_states(rng),
        nn::random_uniform<double>(2, 4, rng, -1, 1)};
    const auto hamiltonian = [&](const std::vector<Var<double>>& in) {
      return ad::sum(ad::sin(mechanics.hamiltonian_field(in[0], in[1], mechanics.known_masses())));
    };
    const auto lagrangian = [&](const std::vector<Var<double>>& in) {
      return ad::sum(ad::sin(mechanics.lagrangian_field(in[0], in[1], mechanics.known_masses())));
    };
    for (const ad::CheckResult& check :
         {ad::gradcheck(hamiltonian, inputs), ad::gradgradcheck(hamiltonian, inputs),
          ad::gradcheck(lagrangian, inputs), ad::gradgradcheck(lagrangian, inputs)}) {
      EXPECT_TRUE(check.ok) << check.worst << "\n" << check.log;
    }
  }
}

TEST(ConstrainedTraining, ATinyRunOnACartesianPendulumReducesTheLoss) {
  // One point on a rod of length 1 from the origin, mass 1, gravity 1: the exact field is the
  // projection of (v, -e_y), which the mechanics give from dV/dx = (0, 1).
  const nn::ConstraintSpec spec = chain_spec({1.0}, 2, Eigen::MatrixXd::Identity(1, 1), {0, 0});
  const MatrixD z = nn::testing::chain_states(spec, 64, 31);
  MatrixD dv = MatrixD::Zero(64, 2);
  dv.col(1).setOnes();
  const MatrixD target = [&] {
    ad::TapeScope scope;
    const nn::ConstrainedMechanics<double> mechanics(spec);
    return mechanics
        .hamiltonian_field(Var<double>::constant(z), Var<double>::constant(dv),
                           mechanics.known_masses())
        .value();
  }();
  std::mt19937_64 rng(32);
  const nn::ConstrainedModel<double> chnn(constrained_config(ModelKind::kChnn, spec, {16, 16}),
                                          rng);
  const std::vector<double> losses = nn::testing::train<double>(chnn, z, target, 150, {.lr = 1e-2});
  EXPECT_LT(losses.back(), 0.05 * losses.front()) << losses.front() << " -> " << losses.back();
}

TEST(ConstrainedTraining, FactoryBuildsNamesAndCastsBothKinds) {
  const nn::ConstraintSpec spec = double_chain();
  const MatrixD z = nn::testing::chain_states(spec, 4, 41);
  for (ModelKind kind : {ModelKind::kChnn, ModelKind::kClnn}) {
    std::mt19937_64 rng(40);
    const auto model = nn::make_model<double>(constrained_config(kind, spec, {8}), rng);
    ASSERT_NE(dynamic_cast<const nn::ConstrainedModel<double>*>(model.get()), nullptr);
    EXPECT_EQ(nn::parse_model_kind(nn::to_string(kind)), kind);
    EXPECT_EQ(model->kind(), std::string(nn::to_string(kind)) + ":tanh");
    EXPECT_EQ(model->mlp().input_dim(), 4);  // the positions only
    EXPECT_EQ(model->named_parameters().front().name, "mlp.layers.0.weight");
    const auto as_float = nn::cast_model<float>(*model);
    const MatrixD back = as_float->field(z.cast<float>()).cast<double>();
    EXPECT_LT((back - model->field(z)).cwiseAbs().maxCoeff(), 1e-4);
  }
}

TEST(ConstrainedTraining, ConfigsThatCannotMakeTheModelAreRefused) {
  const nn::ConstraintSpec spec = double_chain();
  nn::DynamicsConfig config = constrained_config(ModelKind::kChnn, spec, {4});
  const auto refused = [&](const nn::DynamicsConfig& c, const std::string& part) {
    const std::string message = config_error(c);
    EXPECT_NE(message.find(part), std::string::npos)
        << "'" << message << "' lacks '" << part << "'";
  };
  nn::DynamicsConfig c = config;
  c.constraints = {};
  refused(c, "needs the constrained system");
  c = config;
  c.dim = 6;
  refused(c, "has dim 8, got 6");
  c = config;
  c.angles = 1;
  refused(c, "no angles, no input_scale");
  c = config;
  c.model = ModelKind::kHnn;
  refused(c, "a hnn model takes no constraints");
  c = config;
  c.constraints.mass(0, 1) = 0.5;
  refused(c, "not symmetric");
  c = config;
  c.constraints.mass << 1, 2, 2, 1;
  refused(c, "not positive definite");
  c = config;
  c.constraints.links.push_back({1, 0, 0.8});
  refused(c, "already joined");
  c = config;
  c.constraints.links[0].j = 0;
  refused(c, "joins a point to itself");
  c = config;
  c.constraints.links[0].j = 5;
  refused(c, "names point 5, outside [0, 2)");
  c = config;
  c.constraints.anchors[0].point = {1.0};
  refused(c, "fixed point of 1 coordinates in 2 dimensions");
  c = config;
  c.constraints.anchors[0].length = 0;
  refused(c, "has length 0");
  c = config;
  c.constraints.pins.push_back({{1.0}, {0.0, 0.0}});
  refused(c, "pin 0 needs 2 finite weights (one per point), got 1");
  c.constraints.pins[0].weights = {0.0, 0.0};
  refused(c, "pin 0 has only zero weights");
  c.constraints.pins[0].weights = {0.5, 0.5};
  c.constraints.pins[0].point = {0.0, 0.0, 1.0};
  refused(c, "pin 0 needs a fixed point of 2 finite coordinates, got 3");
}
