// The fused tanh-MLP ops against the same networks written with elementary ops: values, first
// derivatives (the hand-written threaded backward), second derivatives (the recorded backward),
// finite differences, thread counts, and shape errors.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "mlp_test_util.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_matrix;
using VarD = Var<double>;

namespace {

using ad::testing::generic_input_gradient;
using ad::testing::generic_mlp;
using ad::testing::inputs_of;
using ad::testing::Layout;
using ad::testing::Net;
using ad::testing::net_of;
using ad::testing::parameters;

const std::vector<Layout> kLayouts = {
    {{3, 5, 4, 1}, false}, {{2, 6, 1}, true}, {{4, 1}, false}, {{2, 4, 3, 5, 1}, false}};
const std::vector<Layout> kMultiOutput = {{{3, 5, 4, 2}, true}, {{2, 6, 3}, false}};

class FusedMlp : public ::testing::TestWithParam<Layout> {};

TEST_P(FusedMlp, ValueAndFirstDerivativesMatchTheGenericNetwork) {
  const Layout l = GetParam();
  const std::vector<MatrixD> in = inputs_of(random_matrix(150, l.widths[0], 1), parameters(l, 2));
  ad::TapeScope scope;
  std::vector<VarD> vars;
  for (const MatrixD& m : in) vars.push_back(VarD::leaf(m));
  const Net<double> net = net_of(vars, l);
  const MatrixD g = random_matrix(150, l.widths.back(), 3);
  const VarD fused = ad::tanh_mlp(vars[0], net.weights, net.biases);
  const VarD generic = generic_mlp(vars[0], net);
  EXPECT_LT((fused.value() - generic.value()).cwiseAbs().maxCoeff(), 1e-13);
  const auto gf = ad::grad<double>({fused}, vars, {}, {VarD::constant(g)});
  const auto gg = ad::grad<double>({generic}, vars, {}, {VarD::constant(g)});
  for (std::size_t i = 0; i < vars.size(); ++i) {
    EXPECT_LT((gf[i].value() - gg[i].value()).cwiseAbs().maxCoeff(), 1e-12) << "input " << i;
  }
}

// Several outputs: every dy_j/dx side by side (mlp_columns_test.cpp checks them further).
TEST_P(FusedMlp, InputGradientAndItsDerivativesMatchDoubleBackpropagation) {
  const Layout l = GetParam();
  const std::vector<MatrixD> in = inputs_of(random_matrix(150, l.widths[0], 4), parameters(l, 5));
  ad::TapeScope scope;
  std::vector<VarD> vars;
  for (const MatrixD& m : in) vars.push_back(VarD::leaf(m));
  const Net<double> net = net_of(vars, l);
  const MatrixD g = random_matrix(150, l.widths[0] * l.widths.back(), 6);
  const VarD fused = ad::tanh_mlp_input_gradient(vars[0], net.weights, net.biases);
  const VarD generic = l.widths.back() == 1 ? generic_input_gradient(vars[0], net)
                                            : ad::testing::generic_input_gradients(vars[0], net);
  EXPECT_LT((fused.value() - generic.value()).cwiseAbs().maxCoeff(), 1e-13);
  const ad::GradOptions unused{.allow_unused = true};
  const auto gf = ad::grad<double>({fused}, vars, unused, {VarD::constant(g)});
  const auto gg = ad::grad<double>({generic}, vars, unused, {VarD::constant(g)});
  for (std::size_t i = 0; i < vars.size(); ++i) {
    EXPECT_LT((gf[i].value() - gg[i].value()).cwiseAbs().maxCoeff(), 1e-12) << "input " << i;
  }
}

TEST_P(FusedMlp, PassesFirstAndSecondOrderGradientChecks) {
  const Layout l = GetParam();
  const std::vector<MatrixD> in = inputs_of(random_matrix(5, l.widths[0], 7), parameters(l, 8));
  const auto forward = [&](const std::vector<VarD>& v) {
    const Net<double> net = net_of(v, l);
    return ad::tanh_mlp(v[0], net.weights, net.biases);
  };
  ad::CheckResult r = ad::gradcheck(forward, in);
  EXPECT_TRUE(r.ok) << r.log;
  r = ad::gradgradcheck(forward, in);
  EXPECT_TRUE(r.ok) << r.log;
  const auto gradient = [&](const std::vector<VarD>& v) {
    const Net<double> net = net_of(v, l);
    return ad::tanh_mlp_input_gradient(v[0], net.weights, net.biases);
  };
  // The last bias does not reach dy/dx: leave it out of the checked inputs.
  std::vector<MatrixD> used = in;
  if (l.last_bias) used.pop_back();
  const auto gradient_of_used = [&](const std::vector<VarD>& v) {
    std::vector<VarD> all = v;
    if (l.last_bias) all.push_back(VarD::leaf(in.back()));
    return gradient(all);
  };
  r = ad::gradcheck(gradient_of_used, used);
  EXPECT_TRUE(r.ok) << r.log;
  r = ad::gradgradcheck(gradient_of_used, used);
  EXPECT_TRUE(r.ok) << r.log;
}

INSTANTIATE_TEST_SUITE_P(Layouts, FusedMlp, ::testing::ValuesIn([] {
                           auto all = kLayouts;
                           all.insert(all.end(), kMultiOutput.begin(), kMultiOutput.end());
                           return all;
                         }()),
                         [](const auto& info) { return info.param.name(); });

// The HNN training step through the fused op equals the generic one, in float and double, for
// 1 and 2 threads (the batch is split into row blocks whose partial sums are reduced in order).
template <typename T>
std::vector<ad::Matrix<T>> hnn_step_gradients(bool fused, int threads) {
  ad::set_num_threads(threads);
  const Layout l{{2, 40, 40, 1}, false};
  const std::vector<MatrixD> p = parameters(l, 11);
  ad::TapeScope scope;
  std::vector<Var<T>> vars{Var<T>::constant(random_matrix(300, 2, 12).cast<T>())};
  for (const MatrixD& m : p)
    if (m.size() > 0) vars.push_back(Var<T>::leaf(m.cast<T>()));
  const Net<T> net = net_of(vars, l);
  const Var<T> x = Var<T>::leaf(vars[0].value());
  const Var<T> dh = fused ? ad::tanh_mlp_input_gradient(vars[0], net.weights, net.biases)
                          : generic_input_gradient(x, net);
  const Var<T> target = Var<T>::constant(random_matrix(300, 2, 13).cast<T>());
  const Var<T> loss = ad::mean(ad::square(dh - target));
  const std::vector<Var<T>> params(vars.begin() + 1, vars.end());
  std::vector<ad::Matrix<T>> out;
  for (const Var<T>& g : ad::grad<T>({loss}, params)) out.push_back(g.value());
  ad::set_num_threads(2);
  return out;
}

}  // namespace

TEST(FusedMlpStep, MatchesTheGenericStepForOneAndTwoThreads) {
  const auto reference = hnn_step_gradients<double>(false, 1);
  for (int threads : {1, 2}) {
    const auto fused = hnn_step_gradients<double>(true, threads);
    ASSERT_EQ(fused.size(), reference.size());
    for (std::size_t i = 0; i < fused.size(); ++i) {
      const double scale = reference[i].cwiseAbs().maxCoeff();
      EXPECT_LT((fused[i] - reference[i]).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << "parameter " << i << ", " << threads << " threads";
    }
    const auto fused_float = hnn_step_gradients<float>(true, threads);
    for (std::size_t i = 0; i < fused.size(); ++i) {
      const double scale = reference[i].cwiseAbs().maxCoeff();
      EXPECT_LT((fused_float[i].template cast<double>() - reference[i]).cwiseAbs().maxCoeff(),
                1e-4 * scale)
          << "float parameter " << i << ", " << threads << " threads";
    }
  }
}

// A weight reached by several ops in one sweep: the fused kernels add their products into the
// sweep's sum in place (Note [Sums added into in place]), whether that sum is still empty, holds
// another op's gradient, or is already the sweep's own. Either order of the three ops against the
// same network written with elementary ops.
TEST(FusedMlpStep, SeveralOpsOnOneWeightSumTheirGradients) {
  ad::set_num_threads(1);
  const Layout l{{3, 16, 16, 1}, false};
  const std::vector<MatrixD> p = parameters(l, 21);
  for (bool generic_last : {false, true}) {
    ad::TapeScope scope;
    std::vector<VarD> vars{VarD::constant(random_matrix(40, 3, 22))};
    for (const MatrixD& m : p) {
      if (m.size() > 0) vars.push_back(VarD::leaf(m));
    }
    const Net<double> net = net_of(vars, l);
    const std::vector<VarD> params(vars.begin() + 1, vars.end());
    std::vector<VarD> xs;
    for (int i = 0; i < 3; ++i) xs.push_back(VarD::variable(random_matrix(40, 3, 23 + i)));
    const auto losses = [&](bool fused) {
      const auto field = [&](const VarD& x) {
        return fused ? ad::tanh_mlp_input_gradient(x, net.weights, net.biases)
                     : generic_input_gradient(x, net);
      };
      const VarD a = ad::sum(ad::square(field(xs[0])));
      const VarD middle = generic_last ? field(xs[1]) : generic_mlp(xs[1], net);
      const VarD last = generic_last ? generic_mlp(xs[2], net) : field(xs[2]);
      return a + ad::sum(ad::square(middle)) + ad::sum(ad::square(last));
    };
    const auto fused = ad::grad<double>({losses(true)}, params);
    const auto reference = ad::grad<double>({losses(false)}, params);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const double scale = reference[i].value().cwiseAbs().maxCoeff();
      EXPECT_LT((fused[i].value() - reference[i].value()).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << "parameter " << i << (generic_last ? ", generic op last" : ", fused op last");
    }
  }
  ad::set_num_threads(2);
}

TEST(FusedMlpStep, SameThreadCountGivesBitIdenticalGradients) {
  EXPECT_EQ(hnn_step_gradients<double>(true, 2), hnn_step_gradients<double>(true, 2));
}

TEST(FusedMlpErrors, NameTheOpTheLayerAndTheShapes) {
  ad::TapeScope scope;
  const VarD x = VarD::constant(MatrixD::Zero(4, 3));
  const VarD w1 = VarD::leaf(MatrixD::Zero(2, 5)), w2 = VarD::leaf(MatrixD::Zero(5, 2));
  try {
    ad::tanh_mlp<double>(x, {w1, w2}, {VarD(), VarD()});
    FAIL() << "no error for a 4x3 input to a 2x5 weight";
  } catch (const ad::Error& e) {
    EXPECT_NE(std::string(e.what()).find("tanh_mlp: layer 1 weight is 2x5"), std::string::npos)
        << e.what();
  }
  const VarD x2 = VarD::constant(MatrixD::Zero(4, 2));
  // Two outputs: both input gradients side by side, 4 x (2 * 2).
  EXPECT_EQ(ad::tanh_mlp_input_gradient<double>(x2, {w1, w2}, {VarD(), VarD()}).shape(), "4x4");
  EXPECT_THROW(ad::tanh_mlp<double>(x2, {w1}, {}), ad::Error);
}

TEST(FusedMlpLayout, HasNoLayerCap) {
  // 40 layers of width 3 (past the 30 a bit mask in a double once allowed), biases on odd ones.
  Layout l{std::vector<Eigen::Index>(41, 3), false};
  l.widths.back() = 1;
  std::vector<MatrixD> p = parameters(l, 40);
  for (std::size_t i = 1; i < p.size(); i += 4) p[i] = MatrixD();  // every other layer: no bias
  const std::vector<MatrixD> in = inputs_of(random_matrix(9, 3, 41), p);
  ad::TapeScope scope;
  std::vector<VarD> vars;
  for (const MatrixD& m : in) vars.push_back(VarD::leaf(m));
  Net<double> net;
  std::size_t k = 1;
  for (std::size_t i = 0; i < p.size(); i += 2) {
    net.weights.push_back(vars[k++]);
    net.biases.push_back(p[i + 1].size() > 0 ? vars[k++] : VarD());
  }
  EXPECT_LT(
      (ad::tanh_mlp(vars[0], net.weights, net.biases).value() - generic_mlp(vars[0], net).value())
          .cwiseAbs()
          .maxCoeff(),
      1e-13);
  const auto gf = ad::grad<double>({ad::sum(ad::tanh_mlp(vars[0], net.weights, net.biases))}, vars);
  const auto gg = ad::grad<double>({ad::sum(generic_mlp(vars[0], net))}, vars);
  for (std::size_t i = 0; i < vars.size(); ++i) {
    EXPECT_LT((gf[i].value() - gg[i].value()).cwiseAbs().maxCoeff(), 1e-12) << "input " << i;
  }
}

TEST(FusedMlpLayout, TypedStateIsKeptByTheRecycledNode) {
  const Layout l{{2, 6, 1}, false};
  const std::vector<MatrixD> p = parameters(l, 42);
  const VarD x = VarD::constant(random_matrix(4, 2, 43));
  const VarD w1 = VarD::leaf(p[0]), b1 = VarD::leaf(p[1]), w2 = VarD::leaf(p[2]);
  const ad::OpState* state = nullptr;
  for (int step = 0; step < 3; ++step) {
    ad::TapeScope scope;
    const VarD y = ad::tanh_mlp<double>(x, {w1, w2}, {b1, VarD()});
    ASSERT_NE(y.node().state, nullptr);
    if (step > 0) {
      EXPECT_EQ(y.node().state.get(), state) << "step " << step;
    }
    state = y.node().state.get();
  }
}
