// Linear, Mlp and Autoencoder: forward values, parameter names and ownership, gradients.

#include <gtest/gtest.h>

#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;

namespace {

std::vector<std::string> names_of(const nn::Module<double>& m) {
  std::vector<std::string> names;
  for (const auto& p : m.named_parameters()) names.push_back(p.name);
  return names;
}

// gradcheck of module(x) with respect to x and every parameter.
template <typename M, typename F>
ad::CheckResult check_module(M& module, const MatrixD& x, F forward, bool second_order = false) {
  std::vector<MatrixD> inputs{x};
  for (const Var<double>& p : module.parameters()) inputs.push_back(p.value());
  const auto f = [&](const std::vector<Var<double>>& in) {
    module.bind_parameters(std::vector<Var<double>>(in.begin() + 1, in.end()));
    return forward(in[0]);
  };
  return second_order ? ad::gradgradcheck(f, inputs) : ad::gradcheck(f, inputs);
}

}  // namespace

TEST(Linear, ComputesXWPlusBAndNamesItsParameters) {
  std::mt19937_64 rng(1);
  nn::Linear<double> layer(3, 2, rng);
  EXPECT_EQ(names_of(layer), (std::vector<std::string>{"weight", "bias"}));
  EXPECT_EQ(layer.weight().rows(), 3);
  EXPECT_EQ(layer.bias().cols(), 2);
  const MatrixD x = nn::random_normal<double>(4, 3, rng);
  ad::TapeScope scope;
  const MatrixD y = layer.forward(Var<double>::constant(x)).value();
  const MatrixD expected = (x * layer.weight().value()).rowwise() + layer.bias().value().row(0);
  EXPECT_TRUE(y.isApprox(expected, 1e-14));

  nn::Linear<double> no_bias(3, 2, rng, nn::Init::kOrthogonal, /*bias=*/false);
  EXPECT_FALSE(no_bias.has_bias());
  EXPECT_EQ(names_of(no_bias), (std::vector<std::string>{"weight"}));
  EXPECT_EQ(no_bias.parameter_count(), 6);
  const ad::CheckResult r =
      check_module(layer, x, [&](const Var<double>& in) { return layer.forward(in); });
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST(Linear, RejectsMismatchedShapes) {
  EXPECT_THROW(nn::Linear<double>(MatrixD::Zero(3, 2), MatrixD::Zero(1, 3)), std::invalid_argument);
  std::mt19937_64 rng(2);
  const nn::Linear<double> layer(3, 2, rng);
  ad::TapeScope scope;
  EXPECT_THROW(layer.forward(Var<double>::constant(MatrixD::Zero(4, 5))), ad::Error);
}

TEST(Mlp, StacksLayersWithTheActivationBetweenThem) {
  std::mt19937_64 rng(3);
  const nn::MlpConfig config{{3, 5, 4, 2}, nn::Activation::kTanh, nn::Init::kOrthogonal, false};
  nn::Mlp<double> mlp(config, rng);
  EXPECT_EQ(names_of(mlp),
            (std::vector<std::string>{"layers.0.weight", "layers.0.bias", "layers.1.weight",
                                      "layers.1.bias", "layers.2.weight"}));
  EXPECT_EQ(mlp.parameter_count(), 3 * 5 + 5 + 5 * 4 + 4 + 4 * 2);
  EXPECT_EQ(mlp.kind(), "mlp:tanh");
  EXPECT_EQ(nn::describe(config), "3-5-4-2 tanh orthogonal nobias");
  const MatrixD x = nn::random_normal<double>(6, 3, rng);
  ad::TapeScope scope;
  const auto& l = mlp.layers();
  const auto affine = [](const MatrixD& h, const nn::Linear<double>& layer) {
    MatrixD out = h * layer.weight().value();
    if (layer.has_bias()) out.rowwise() += layer.bias().value().row(0);
    return out;
  };
  const MatrixD expected =
      affine(affine(affine(x, l[0]).array().tanh().matrix(), l[1]).array().tanh().matrix(), l[2]);
  EXPECT_TRUE(mlp.forward(Var<double>::constant(x)).value().isApprox(expected, 1e-14));
}

TEST(Mlp, EveryActivationMatchesFiniteDifferences) {
  for (const nn::Activation act :
       {nn::Activation::kTanh, nn::Activation::kRelu, nn::Activation::kSigmoid,
        nn::Activation::kSoftplus, nn::Activation::kElu, nn::Activation::kSelu,
        nn::Activation::kSwish}) {
    std::mt19937_64 rng(4);
    nn::Mlp<double> mlp({{3, 4, 4, 2}, act, nn::Init::kXavierNormal, true}, rng);
    const MatrixD x = nn::random_normal<double>(3, 3, rng);
    const auto forward = [&](const Var<double>& in) { return mlp.forward(in); };
    const ad::CheckResult first = check_module(mlp, x, forward);
    EXPECT_TRUE(first.ok) << nn::to_string(act) << ": " << first.worst << "\n" << first.log;
    if (act == nn::Activation::kRelu) continue;  // relu'' is zero almost everywhere
    const ad::CheckResult second = check_module(mlp, x, forward, /*second_order=*/true);
    EXPECT_TRUE(second.ok) << nn::to_string(act) << ": " << second.worst << "\n" << second.log;
  }
}

TEST(Mlp, InputGradientOfEachColumnMatchesFiniteDifferencesToSecondOrder) {
  // tanh: one fused op on the column's slice of the last weight; softplus: ad::grad.
  for (const nn::Activation act : {nn::Activation::kTanh, nn::Activation::kSoftplus}) {
    std::mt19937_64 rng(6);
    nn::Mlp<double> mlp({{3, 5, 4, 3}, act, nn::Init::kXavierNormal, false}, rng);
    const MatrixD x = nn::random_normal<double>(4, 3, rng);
    for (Eigen::Index column = 0; column < 3; ++column) {
      const auto gradient = [&](const Var<double>& in) { return mlp.input_gradient(in, column); };
      const ad::CheckResult first = check_module(mlp, x, gradient);
      EXPECT_TRUE(first.ok) << nn::to_string(act) << " column " << column << ": " << first.log;
      const ad::CheckResult second = check_module(mlp, x, gradient, /*second_order=*/true);
      EXPECT_TRUE(second.ok) << nn::to_string(act) << " column " << column << ": " << second.log;
    }
    ad::TapeScope scope;
    EXPECT_THROW(mlp.input_gradient(Var<double>::constant(x), 3), std::invalid_argument);
    EXPECT_THROW(mlp.input_gradient(Var<double>::constant(x), -1), std::invalid_argument);
  }
}

TEST(Mlp, NamesAndConfigErrorsAreClear) {
  std::mt19937_64 rng(5);
  EXPECT_THROW(nn::Mlp<double>({{3}}, rng), std::invalid_argument);
  EXPECT_THROW(nn::Mlp<double>({{3, 0, 1}}, rng), std::invalid_argument);
  EXPECT_EQ(nn::parse_activation("swish"), nn::Activation::kSwish);
  try {
    nn::parse_activation("gelu");
    FAIL() << "gelu was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tanh, relu, sigmoid"), std::string::npos) << e.what();
  }
}

TEST(Mlp, SameSeedGivesBitIdenticalParametersAndCastsAreDeepCopies) {
  const nn::MlpConfig config{{2, 16, 16, 1}};
  std::mt19937_64 a(7), b(7), c(7);
  const nn::Mlp<double> m1(config, a), m2(config, b);
  const nn::Mlp<float> f1(config, c);
  const auto p1 = m1.parameters(), p2 = m2.parameters();
  const auto pf = f1.parameters();
  for (std::size_t i = 0; i < p1.size(); ++i) {
    EXPECT_EQ(p1[i].value(), p2[i].value());
    // Drawn in double and rounded: a float model is the double model rounded.
    EXPECT_EQ(pf[i].value(), p1[i].value().cast<float>());
  }
  nn::Mlp<float> cast = m1.cast<float>();
  nn::Mlp<double> clone = m1.cast<double>();
  EXPECT_EQ(clone.parameters()[0].value(), p1[0].value());
  clone.parameters()[0].mutable_value().setZero();
  EXPECT_NE(clone.parameters()[0].value(), p1[0].value());
  EXPECT_EQ(cast.parameters()[2].value(), p1[2].value().cast<float>());
}

TEST(Module, CopyParametersChecksNamesAndShapesBeforeCopying) {
  std::mt19937_64 rng(8);
  const nn::Mlp<double> from({{2, 8, 1}}, rng);
  nn::Mlp<float> to({{2, 8, 1}}, rng);
  nn::copy_parameters(from, to);
  EXPECT_EQ(to.parameters()[1].value(), from.parameters()[1].value().cast<float>());
  nn::Mlp<float> other({{2, 9, 1}}, rng);
  const nn::Matrix<float> before = other.parameters()[0].value();
  EXPECT_THROW(nn::copy_parameters(from, other), std::invalid_argument);
  EXPECT_EQ(other.parameters()[0].value(), before);
  EXPECT_THROW(other.bind_parameters({}), std::invalid_argument);
}

TEST(Module, SetRequiresGradFreezesParameters) {
  std::mt19937_64 rng(9);
  nn::Mlp<double> mlp({{2, 3, 1}}, rng);
  mlp.set_requires_grad(false);
  for (const auto& p : mlp.parameters()) EXPECT_FALSE(p.requires_grad());
  mlp.set_requires_grad(true);
  for (const auto& p : mlp.parameters()) EXPECT_TRUE(p.requires_grad());
}

TEST(Autoencoder, HasResidualInnerLayersAndThePaperShape) {
  std::mt19937_64 rng(10);
  const nn::Autoencoder<float> paper({}, rng);
  EXPECT_EQ(paper.encoder()[0].in_features(), 1568);
  EXPECT_EQ(paper.encoder()[3].out_features(), 2);
  EXPECT_EQ(paper.decoder()[3].out_features(), 1568);
  EXPECT_EQ(paper.kind(), "autoencoder:relu");
  EXPECT_EQ(paper.named_parameters().size(), 16u);
  EXPECT_EQ(paper.named_parameters()[0].name, "encoder.0.weight");
  EXPECT_EQ(paper.named_parameters()[15].name, "decoder.3.bias");

  nn::AutoencoderConfig config;
  config.input_dim = 6;
  config.hidden_dim = 5;
  config.latent_dim = 2;
  nn::Autoencoder<double> ae(config, rng);
  const MatrixD x = nn::random_normal<double>(4, 6, rng);
  const auto relu = [](const MatrixD& m) { return MatrixD(m.cwiseMax(0.0)); };
  const auto affine = [](const MatrixD& h, const nn::Linear<double>& layer) {
    return MatrixD((h * layer.weight().value()).rowwise() + layer.bias().value().row(0));
  };
  const auto half = [&](const std::array<nn::Linear<double>, 4>& l, const MatrixD& in) {
    MatrixD h = relu(affine(in, l[0]));
    h = h + relu(affine(h, l[1]));
    h = h + relu(affine(h, l[2]));
    return affine(h, l[3]);
  };
  ad::TapeScope scope;
  const MatrixD z = ae.encode(Var<double>::constant(x)).value();
  EXPECT_TRUE(z.isApprox(half(ae.encoder(), x), 1e-14));
  EXPECT_TRUE(ae.forward(Var<double>::constant(x)).value().isApprox(half(ae.decoder(), z), 1e-14));
  const ad::CheckResult r =
      check_module(ae, x, [&](const Var<double>& in) { return ae.forward(in); });
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
  const nn::Autoencoder<float> cast = ae.cast<float>();
  EXPECT_EQ(cast.decoder()[2].bias().value(), ae.decoder()[2].bias().value().cast<float>());
}
