// The HNN and baseline models: derivatives against finite differences, the structure of the
// learned field (divergence-free, H conserved, gradient fields), and short training runs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;
using nn::FieldType;
using nn::ModelKind;
using nn::testing::small_config;

namespace {

MatrixD random_states(Eigen::Index rows, Eigen::Index dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return nn::random_uniform<double>(rows, dim, rng, -1.0, 1.0);
}

// The loss of one training step, as a function of (x, parameters...), for gradcheck.
auto loss_of(const nn::DynamicsModel<double>& model, const MatrixD& target) {
  return [&model, target](const std::vector<Var<double>>& in) {
    const_cast<nn::DynamicsModel<double>&>(model).bind_parameters(
        std::vector<Var<double>>(in.begin() + 1, in.end()));
    return nn::mse(model.time_derivative(in[0]), Var<double>::constant(target));
  };
}

std::vector<MatrixD> inputs_of(const nn::DynamicsModel<double>& model, const MatrixD& x) {
  std::vector<MatrixD> inputs{x};
  for (const Var<double>& p : model.parameters()) inputs.push_back(p.value());
  return inputs;
}

}  // namespace

TEST(Hnn, TimeDerivativeIsTheSymplecticGradientOfTheEnergy) {
  std::mt19937_64 rng(1);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 4, {8, 8}), rng);
  const MatrixD x = random_states(5, 4, 2);
  ad::TapeScope scope;
  const Var<double> xv = Var<double>::leaf(x);
  const MatrixD dh = ad::grad<double>({ad::sum(hnn.energy(xv))}, {xv})[0].value();
  const MatrixD f = hnn.time_derivative(xv).value();
  EXPECT_EQ(f.leftCols(2), dh.rightCols(2));
  EXPECT_EQ(f.rightCols(2), -dh.leftCols(2));
  EXPECT_EQ(hnn.field(x), f);
}

TEST(Hnn, TrainingLossMatchesFiniteDifferencesUpToSecondOrder) {
  for (const FieldType field : {FieldType::kSolenoidal, FieldType::kBoth}) {
    std::mt19937_64 rng(3);
    const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {5, 4}, field), rng);
    const MatrixD x = random_states(4, 2, 4), target = random_states(4, 2, 5);
    const ad::CheckResult first = ad::gradcheck(loss_of(hnn, target), inputs_of(hnn, x));
    EXPECT_TRUE(first.ok) << nn::to_string(field) << ": " << first.worst << "\n" << first.log;
    const ad::CheckResult second = ad::gradgradcheck(loss_of(hnn, target), inputs_of(hnn, x));
    EXPECT_TRUE(second.ok) << nn::to_string(field) << ": " << second.worst << "\n" << second.log;
  }
}

TEST(Hnn, FieldOfEveryActivationAndFieldTypeMatchesFiniteDifferences) {
  for (const FieldType field :
       {FieldType::kSolenoidal, FieldType::kConservative, FieldType::kBoth}) {
    for (const nn::Activation act :
         {nn::Activation::kTanh, nn::Activation::kSigmoid, nn::Activation::kSoftplus,
          nn::Activation::kElu, nn::Activation::kSelu, nn::Activation::kSwish}) {
      std::mt19937_64 rng(6);
      const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 4, {6}, field, act), rng);
      const auto f = [&](const std::vector<Var<double>>& in) {
        const_cast<nn::Hnn<double>&>(hnn).bind_parameters(
            std::vector<Var<double>>(in.begin() + 1, in.end()));
        return hnn.time_derivative(in[0]);
      };
      const ad::CheckResult r = ad::gradcheck(f, inputs_of(hnn, random_states(3, 4, 7)));
      EXPECT_TRUE(r.ok) << nn::to_string(field) << ", " << nn::to_string(act) << ": " << r.worst
                        << "\n"
                        << r.log;
    }
  }
}

TEST(Hnn, FieldIsDivergenceFreeAndConservesTheLearnedEnergy) {
  std::mt19937_64 rng(8);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 4, {16, 16}), rng);
  const MatrixD x = random_states(20, 4, 9);
  const MatrixD f = hnn.field(x);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const MatrixD jac = ad::jacobian<double>(
        [&](const Var<double>& row) { return hnn.time_derivative(row); }, x.row(i));
    const double scale = jac.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 1e-3);
    EXPECT_LE(std::abs(jac.trace()), 1e-14 * scale) << "row " << i << "\n" << jac;
    // The solenoidal Jacobian is J Hess(H): J^-1 M is symmetric.
    MatrixD hess(4, 4);
    hess << -jac.bottomRows(2), jac.topRows(2);
    EXPECT_LE((hess - hess.transpose()).cwiseAbs().maxCoeff(), 1e-14 * scale);
  }
  // dH/dt along the field: grad H . (dH/dp, -dH/dq) = 0, to rounding.
  ad::TapeScope scope;
  const Var<double> xv = Var<double>::leaf(x);
  const MatrixD dh = ad::grad<double>({ad::sum(hnn.energy(xv))}, {xv})[0].value();
  const Eigen::VectorXd dhdt = (dh.array() * f.array()).rowwise().sum();
  const double scale = (dh.array() * f.array()).abs().maxCoeff();
  EXPECT_LE(dhdt.cwiseAbs().maxCoeff(), 1e-15 * scale + 1e-300);
}

TEST(Hnn, ConservativeFieldIsTheGradientOfTheDissipationAndBothIsTheSum) {
  std::mt19937_64 rng(10);
  const nn::Hnn<double> both(small_config(ModelKind::kHnn, 2, {12}, FieldType::kBoth), rng);
  const MatrixD x = random_states(6, 2, 11);
  ad::TapeScope scope;
  const Var<double> xv = Var<double>::leaf(x);
  const nn::Hnn<double>::Parts parts = both.time_derivative_parts(xv);
  const MatrixD dd = ad::grad<double>({ad::sum(both.dissipation(xv))}, {xv})[0].value();
  // Equal to rounding: the recorded and the fused backward differ in operation order.
  EXPECT_LT((parts.conservative.value() - dd).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((both.field(x) - (parts.solenoidal.value() + parts.conservative.value()))
                .cwiseAbs()
                .maxCoeff(),
            1e-15);
  // A gradient field has a symmetric Jacobian (no curl) and, for a generic D, divergence.
  std::mt19937_64 rng2(12);
  const nn::Hnn<double> conservative(
      small_config(ModelKind::kHnn, 2, {12}, FieldType::kConservative), rng2);
  EXPECT_THROW(conservative.energy(xv), std::logic_error);
  const MatrixD jac = ad::jacobian<double>(
      [&](const Var<double>& row) { return conservative.time_derivative(row); }, x.row(0));
  EXPECT_NEAR(jac(0, 1), jac(1, 0), 1e-14 * jac.cwiseAbs().maxCoeff());
  EXPECT_GT(std::abs(jac.trace()), 1e-6);
}

// The dissipative field (dH/dp, -dH/dq) + dD/dx written with the engine's generic double
// backpropagation through the MLP's forward pass: the formula the fused route must reproduce.
template <typename T>
Var<T> generic_dissipative_field(const nn::Hnn<T>& hnn, const Var<T>& x) {
  const Var<T> out = hnn.mlp().forward(x);
  const auto gradient_of_column = [&](Eigen::Index column) {
    const Var<T> y = ad::slice_cols(out, column, 1);
    return ad::grad<T>({ad::sum(y)}, {x}, {.create_graph = true})[0];
  };
  const Var<T> dh = gradient_of_column(0), dd = gradient_of_column(1);
  const Eigen::Index n = x.cols() / 2;
  return ad::concat_cols<T>({ad::slice_cols(dh, n, n), -ad::slice_cols(dh, 0, n)}) + dd;
}

// The field, the loss's parameter gradients, and second derivatives (the parameter gradient of
// the squared norm of those gradients) of a kBoth HNN, fused or generic.
template <typename T>
std::vector<nn::Matrix<T>> dissipative_derivatives(bool fused) {
  std::mt19937_64 rng(26);
  const nn::Hnn<T> hnn(small_config(ModelKind::kHnn, 4, {16, 16}, FieldType::kBoth), rng);
  ad::TapeScope scope;
  const Var<T> x = Var<T>::leaf(random_states(90, 4, 27).cast<T>());
  const Var<T> target = Var<T>::constant(random_states(90, 4, 28).cast<T>());
  const Var<T> field = fused ? hnn.time_derivative(x) : generic_dissipative_field(hnn, x);
  const std::vector<Var<T>> params = hnn.parameters();
  const std::vector<Var<T>> first =
      ad::grad<T>({nn::mse(field, target)}, params, {.create_graph = true});
  Var<T> norm = ad::sum(ad::square(first[0]));
  for (std::size_t i = 1; i < first.size(); ++i) norm = norm + ad::sum(ad::square(first[i]));
  const std::vector<Var<T>> second = ad::grad<T>({norm}, params, {.allow_unused = true});
  std::vector<nn::Matrix<T>> out{field.value()};
  for (const Var<T>& g : first) out.push_back(g.value());
  for (const Var<T>& g : second) out.push_back(g.value());
  return out;
}

template <typename T>
void expect_dissipative_routes_agree(double tolerance) {
  const auto fused = dissipative_derivatives<T>(true), generic = dissipative_derivatives<T>(false);
  ASSERT_EQ(fused.size(), generic.size());
  for (std::size_t i = 0; i < fused.size(); ++i) {
    const double scale = std::max(1.0, double(generic[i].cwiseAbs().maxCoeff()));
    EXPECT_LT(double((fused[i] - generic[i]).cwiseAbs().maxCoeff()), tolerance * scale)
        << "entry " << i << " (0: field, then first and second derivatives)";
  }
}

// A D-HNN's dH/dx and dD/dx come from one op (input_gradients); with angles seen as (cos, sin)
// and input scales, each block still goes back through the embedding to the state.
TEST(Hnn, BothGradientsGoThroughTheAngleEmbeddingAndTheScales) {
  std::mt19937_64 rng(14);
  nn::DynamicsConfig config = small_config(ModelKind::kDhnn, 2, {12}, FieldType::kBoth);
  config.angles = 1;
  config.input_scale = {1, 3};
  const nn::Hnn<double> model(config, rng);
  const MatrixD x = random_states(6, 2, 15) * 4.0;  // angles across +-pi
  ad::TapeScope scope;
  const Var<double> xv = Var<double>::leaf(x);
  const nn::Hnn<double>::Parts parts = model.time_derivative_parts(xv);
  const MatrixD dh = ad::grad<double>({ad::sum(model.energy(xv))}, {xv})[0].value();
  const MatrixD dd = ad::grad<double>({ad::sum(model.dissipation(xv))}, {xv})[0].value();
  const MatrixD sym = (MatrixD(6, 2) << dh.col(1), -dh.col(0)).finished();
  EXPECT_LT((parts.solenoidal.value() - sym).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((parts.conservative.value() - dd).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Hnn, DissipativeFieldMatchesTheGenericFormulaToSecondOrder) {
  expect_dissipative_routes_agree<double>(1e-12);
  expect_dissipative_routes_agree<float>(1e-4);
}

TEST(Hnn, DerivativeReachesTheModelThatProducedItsInput) {
  // The pixel task feeds an encoder's output z to the HNN: the loss must reach the encoder.
  std::mt19937_64 rng(13);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {6}), rng);
  const MatrixD pixels = random_states(3, 5, 14), target = random_states(3, 2, 15);
  const MatrixD w0 = nn::random_normal<double>(5, 2, rng, 0.0, 0.5);
  const auto f = [&](const std::vector<Var<double>>& in) {
    const Var<double> z = ad::linear(Var<double>::constant(pixels), in[0]);
    return nn::mse(z + hnn.time_derivative(z), Var<double>::constant(target));
  };
  const ad::CheckResult r = ad::gradcheck(f, {w0});
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST(Hnn, UnderNoGradGuardGivesValuesOnly) {
  std::mt19937_64 rng(16);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {8}), rng);
  const MatrixD x = random_states(4, 2, 17);
  ad::TapeScope scope;
  ad::NoGradGuard no_grad;
  const Var<double> f = hnn.time_derivative(Var<double>::constant(x));
  EXPECT_FALSE(f.requires_grad());
  EXPECT_EQ(f.value(), hnn.field(x));
  EXPECT_FALSE(ad::grad_enabled());
}

TEST(Hnn, FieldLeavesNothingOnTheTapeAndRestoresTheGradMode) {
  std::mt19937_64 rng(24);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {8}), rng);
  const MatrixD x = random_states(4, 2, 25);
  const std::size_t before = ad::Tape<double>::current().size();
  const MatrixD f = hnn.field(x);
  EXPECT_EQ(ad::Tape<double>::current().size(), before);
  EXPECT_TRUE(ad::grad_enabled());
  ad::TapeScope scope;
  EXPECT_EQ(f, hnn.time_derivative(Var<double>::leaf(x)).value());
}

TEST(Hnn, RejectsBadInputsAndConfigs) {
  std::mt19937_64 rng(18);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {4}), rng);
  EXPECT_THROW(hnn.field(MatrixD::Zero(3, 4)), ad::Error);
  EXPECT_THROW(nn::Hnn<double>(small_config(ModelKind::kHnn, 3, {4}), rng), std::invalid_argument);
  EXPECT_THROW(nn::Hnn<double>(small_config(ModelKind::kBaseline, 2, {4}), rng),
               std::invalid_argument);
  EXPECT_THROW(nn::parse_field_type("curl"), std::invalid_argument);
  EXPECT_EQ(nn::parse_field_type("both"), FieldType::kBoth);
}

TEST(Baseline, PredictsTheFieldDirectlyWithTheSameInterface) {
  std::mt19937_64 rng(19);
  const auto model = nn::make_model<double>(small_config(ModelKind::kBaseline, 4, {8, 8}), rng);
  EXPECT_EQ(model->name(), "baseline");
  EXPECT_EQ(model->kind(), "baseline:tanh");
  EXPECT_EQ(model->mlp().output_dim(), 4);
  const MatrixD x = random_states(5, 4, 20);
  ad::TapeScope scope;
  EXPECT_EQ(model->field(x), model->mlp().forward(Var<double>::constant(x)).value());
  const ad::CheckResult r =
      ad::gradcheck(loss_of(*model, random_states(5, 4, 21)), inputs_of(*model, x));
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST(Baseline, GivenVelocitiesPredictsTheAccelerationsAlone) {
  std::mt19937_64 rng(23);
  nn::DynamicsConfig config = small_config(ModelKind::kBaseline, 4, {8, 8});
  config.given_velocities = true;
  const auto model = nn::make_model<double>(config, rng);
  EXPECT_EQ(model->mlp().output_dim(), 2);
  const MatrixD x = random_states(5, 4, 24);
  const MatrixD f = model->field(x);
  EXPECT_EQ(f.leftCols(2), x.rightCols(2));  // dq/dt = v, given
  ad::TapeScope scope;
  EXPECT_EQ(f.rightCols(2), model->mlp().forward(Var<double>::constant(x)).value());
  const ad::CheckResult r =
      ad::gradcheck(loss_of(*model, random_states(5, 4, 25)), inputs_of(*model, x));
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
  config.dim = 3;
  EXPECT_THROW(nn::make_model<double>(config, rng), std::invalid_argument);
  config.dim = 4;
  config.model = ModelKind::kLnn;
  EXPECT_THROW(nn::make_model<double>(config, rng), std::invalid_argument);
}

TEST(Models, CastBetweenFloatAndDoubleKeepsPredictions) {
  std::mt19937_64 rng(22);
  const auto model = nn::make_model<double>(small_config(ModelKind::kHnn, 2, {16, 16}), rng);
  const auto as_float = nn::cast_model<float>(*model);
  const auto back = nn::cast_model<double>(*as_float);
  EXPECT_EQ(as_float->kind(), model->kind());
  const MatrixD x = random_states(8, 2, 23);
  const nn::Matrix<float> ff = as_float->field(x.cast<float>());
  EXPECT_LE((ff.cast<double>() - model->field(x)).cwiseAbs().maxCoeff(), 1e-5);
  // A clone is independent: changing it leaves the original alone.
  const auto clone = nn::cast_model<double>(*model);
  EXPECT_EQ(clone->field(x), model->field(x));
  clone->parameters()[0].mutable_value().setZero();
  EXPECT_NE(clone->field(x), model->field(x));
  EXPECT_LE((back->field(x) - model->field(x)).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Training, HnnLearnsTheSpringAndItsEnergyIsConservedAlongATrueOrbit) {
  const nn::testing::SpringData data = nn::testing::spring_data(25, /*seed=*/1);
  std::mt19937_64 rng(2);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 2, {32, 32}), rng);
  const std::vector<double> losses =
      nn::testing::train<double>(hnn, data.x, data.dxdt, 300, {.lr = 1e-3, .weight_decay = 1e-4});
  EXPECT_LT(losses.back(), losses.front() / 8) << losses.front() << " -> " << losses.back();
  EXPECT_LT(losses.back(), 0.06);  // the noise floor is about 0.04 (Table 1: 0.037)

  // H along the true orbit of radius 0.6, against its range over the plane [-1, 1]^2.
  MatrixD orbit(100, 2), grid(21 * 21, 2);
  for (int i = 0; i < 100; ++i) {
    orbit.row(i) << 0.6 * std::cos(0.0628 * i), 0.6 * std::sin(0.0628 * i);
  }
  for (int i = 0; i < 21; ++i) {
    for (int j = 0; j < 21; ++j) grid.row(i * 21 + j) << -1 + 0.1 * i, -1 + 0.1 * j;
  }
  const MatrixD h = hnn.energy(orbit), h_grid = hnn.energy(grid);
  const double mean = h.mean();
  const double std = std::sqrt((h.array() - mean).square().mean());
  const double range = h_grid.maxCoeff() - h_grid.minCoeff();
  EXPECT_LT(std / range, 0.03) << "std " << std << " range " << range;
}

TEST(Training, BaselineTrainsToo) {
  const nn::testing::SpringData data = nn::testing::spring_data(25, /*seed=*/1);
  std::mt19937_64 rng(2);
  const nn::Baseline<double> baseline(small_config(ModelKind::kBaseline, 2, {32, 32}), rng);
  const std::vector<double> losses = nn::testing::train<double>(baseline, data.x, data.dxdt, 300,
                                                                {.lr = 1e-3, .weight_decay = 1e-4});
  EXPECT_LT(losses.back(), losses.front() / 8) << losses.front() << " -> " << losses.back();
}

TEST(Training, SameSeedGivesIdenticalLosses) {
  const nn::testing::SpringData data = nn::testing::spring_data(25, /*seed=*/3);
  const auto run = [&](std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    const auto model = nn::make_model<float>(small_config(ModelKind::kHnn, 2, {16, 16}), rng);
    return nn::testing::train<float>(*model, data.x.cast<float>(), data.dxdt.cast<float>(), 40,
                                     {.lr = 1e-3});
  };
  const std::vector<double> a = run(5), b = run(5), c = run(6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_LT(a.back(), a.front());
}
