// The fused input gradient of one output column of a multi-output tanh MLP (the fused op on the
// column's slice of the last weight, as nn::Mlp::input_gradient runs it), and of every column in
// one op (nn::Mlp::input_gradients, a D-HNN's H and D), against double backpropagation through
// the generic network: values, first and second derivatives, in float and double, and finite
// differences.

#include <gtest/gtest.h>

#include <vector>

#include "autodiff/autodiff.h"
#include "mlp_test_util.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::column_input_gradient;
using ad::testing::generic_column_input_gradient;
using ad::testing::inputs_of;
using ad::testing::Layout;
using ad::testing::MatrixD;
using ad::testing::Net;
using ad::testing::net_of;
using ad::testing::parameters;
using ad::testing::random_matrix;
using VarD = Var<double>;

namespace {

const std::vector<Layout> kMultiOutput = {
    {{3, 5, 4, 2}, true}, {{2, 6, 3}, false}, {{2, 8, 8, 2}, false}, {{3, 2}, true}};

constexpr Eigen::Index kAllColumns = -1;

// A column's input gradient (kAllColumns: every column's, side by side, in one fused op), its
// first derivatives in every input (for a random upstream gradient) and its second derivatives
// (the derivative of <first, v> for a random v), fused or generic.
template <typename T>
std::vector<ad::Matrix<T>> derivatives(const Layout& l, Eigen::Index column, bool fused) {
  const std::vector<MatrixD> in = inputs_of(random_matrix(150, l.widths[0], 21), parameters(l, 22));
  ad::TapeScope scope;
  std::vector<Var<T>> vars;
  for (const MatrixD& m : in) vars.push_back(Var<T>::leaf(m.cast<T>()));
  const Net<T> net = net_of(vars, l);
  Var<T> dy;
  if (column == kAllColumns) {
    dy = fused ? ad::tanh_mlp_input_gradient(vars[0], net.weights, net.biases)
               : ad::testing::generic_input_gradients(vars[0], net);
  } else {
    dy = fused ? column_input_gradient(vars[0], net, column)
               : generic_column_input_gradient(vars[0], net, column);
  }
  const Var<T> g = Var<T>::constant(random_matrix(150, dy.cols(), 23).template cast<T>());
  const ad::GradOptions recorded{.create_graph = true, .allow_unused = true};
  const std::vector<Var<T>> first = ad::grad<T>({dy}, vars, recorded, {g});
  Var<T> projection = ad::sum(first[0] * first[0]);
  for (std::size_t i = 1; i < first.size(); ++i) projection = projection + ad::sum(first[i]);
  std::vector<ad::Matrix<T>> out{dy.value()};
  for (const Var<T>& d : first) out.push_back(d.value());
  if (!projection.requires_grad()) return out;  // no hidden layer: dy/dx is linear in W
  for (const Var<T>& d : ad::grad<T>({projection}, vars, {.allow_unused = true})) {
    out.push_back(d.value());
  }
  return out;
}

// max |a - b| over every matrix, relative to b's largest entry.
template <typename T>
double relative_difference(const std::vector<ad::Matrix<T>>& a,
                           const std::vector<ad::Matrix<T>>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double scale = std::max(1.0, double(b[i].cwiseAbs().maxCoeff()));
    worst = std::max(worst, double((a[i] - b[i]).cwiseAbs().maxCoeff()) / scale);
  }
  return worst;
}

class FusedColumn : public ::testing::TestWithParam<Layout> {};

TEST_P(FusedColumn, MatchesDoubleBackpropagationToSecondOrderInFloatAndDouble) {
  const Layout l = GetParam();
  for (Eigen::Index column = kAllColumns; column < l.widths.back(); ++column) {
    const auto reference = derivatives<double>(l, column, false);
    EXPECT_LT(relative_difference(derivatives<double>(l, column, true), reference), 1e-12)
        << "double, column " << column;
    const auto generic_float = derivatives<float>(l, column, false);
    EXPECT_LT(relative_difference(derivatives<float>(l, column, true), generic_float), 1e-5)
        << "float, column " << column;
  }
}

TEST_P(FusedColumn, PassesFirstAndSecondOrderGradientChecks) {
  const Layout l = GetParam();
  const std::vector<MatrixD> in = inputs_of(random_matrix(5, l.widths[0], 24), parameters(l, 25));
  // The last bias does not reach dy/dx: leave it out of the checked inputs.
  std::vector<MatrixD> used = in;
  if (l.last_bias) used.pop_back();
  for (Eigen::Index column = kAllColumns; column < l.widths.back(); ++column) {
    const auto gradient = [&](const std::vector<VarD>& v) {
      std::vector<VarD> all = v;
      if (l.last_bias) all.push_back(VarD::leaf(in.back()));
      const Net<double> net = net_of(all, l);
      return column == kAllColumns ? ad::tanh_mlp_input_gradient(all[0], net.weights, net.biases)
                                   : column_input_gradient(all[0], net, column);
    };
    ad::CheckResult r = ad::gradcheck(gradient, used);
    EXPECT_TRUE(r.ok) << "column " << column << ": " << r.log;
    r = ad::gradgradcheck(gradient, used);
    EXPECT_TRUE(r.ok) << "column " << column << ": " << r.log;
  }
}

INSTANTIATE_TEST_SUITE_P(Layouts, FusedColumn, ::testing::ValuesIn(kMultiOutput),
                         [](const auto& info) { return info.param.name(); });

}  // namespace
