#pragma once
// Shared helpers of the fused-MLP tests: layouts, their parameters, and the same networks
// written with elementary ops (the reference the fused ops are checked against).

#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace hnn::ad::testing {

// An MLP layout: widths and whether the last layer has a bias.
struct Layout {
  std::vector<Eigen::Index> widths;
  bool last_bias;
  std::string name() const {
    std::string s;
    for (auto w : widths) s += std::to_string(w) + "_";
    return s + (last_bias ? "bias" : "nobias");
  }
};

// Parameter values W1, b1, W2, b2, ... (the last bias empty when absent).
inline std::vector<MatrixD> parameters(const Layout& l, unsigned seed) {
  std::vector<MatrixD> p;
  for (std::size_t i = 0; i + 1 < l.widths.size(); ++i) {
    p.push_back(random_matrix(l.widths[i], l.widths[i + 1], seed + 2 * unsigned(i), -0.8, 0.8));
    const bool bias = i + 2 < l.widths.size() || l.last_bias;
    p.push_back(bias ? random_matrix(1, l.widths[i + 1], seed + 2 * unsigned(i) + 1, -0.5, 0.5)
                     : MatrixD());
  }
  return p;
}

template <typename T>
struct Net {
  std::vector<Var<T>> weights, biases;
};

// Splits {x, W1, b1, ...} Vars (empty-matrix biases skipped) into a Net.
template <typename T>
Net<T> net_of(const std::vector<Var<T>>& in, const Layout& l) {
  Net<T> net;
  std::size_t k = 1;
  for (std::size_t i = 0; i + 1 < l.widths.size(); ++i) {
    net.weights.push_back(in[k++]);
    const bool bias = i + 2 < l.widths.size() || l.last_bias;
    net.biases.push_back(bias ? in[k++] : Var<T>());
  }
  return net;
}

// The inputs as a list for the checks: x then the parameters that exist.
inline std::vector<MatrixD> inputs_of(const MatrixD& x, const std::vector<MatrixD>& params) {
  std::vector<MatrixD> in{x};
  for (const MatrixD& p : params)
    if (p.size() > 0) in.push_back(p);
  return in;
}

template <typename T>
Var<T> generic_mlp(const Var<T>& x, const Net<T>& net) {
  Var<T> h = x;
  for (std::size_t i = 0; i < net.weights.size(); ++i) {
    h = ad::linear(h, net.weights[i], net.biases[i]);
    if (i + 1 < net.weights.size()) h = ad::tanh(h);
  }
  return h;
}

// dy/dx through the engine's generic double backpropagation.
template <typename T>
Var<T> generic_input_gradient(const Var<T>& x, const Net<T>& net) {
  return ad::grad<T>({ad::sum(generic_mlp(x, net))}, {x}, {.create_graph = true})[0];
}

// d y[:, column] / dx through the fused op, on the column's slice of the last weight (how
// nn::Mlp::input_gradient runs a tanh MLP with several outputs).
template <typename T>
Var<T> column_input_gradient(const Var<T>& x, const Net<T>& net, Eigen::Index column) {
  std::vector<Var<T>> weights = net.weights;
  weights.back() = ad::slice_cols(weights.back(), column, 1);
  return ad::tanh_mlp_input_gradient(x, weights, net.biases);
}

// The same through the engine's generic double backpropagation.
template <typename T>
Var<T> generic_column_input_gradient(const Var<T>& x, const Net<T>& net, Eigen::Index column) {
  const Var<T> y = ad::slice_cols(generic_mlp(x, net), column, 1);
  return ad::grad<T>({ad::sum(y)}, {x}, {.create_graph = true})[0];
}

// Every output's dy_j/dx side by side (what the fused op gives for several outputs), through the
// generic double backpropagation.
template <typename T>
Var<T> generic_input_gradients(const Var<T>& x, const Net<T>& net) {
  std::vector<Var<T>> columns;
  for (Eigen::Index j = 0; j < net.weights.back().cols(); ++j)
    columns.push_back(generic_column_input_gradient(x, net, j));
  return ad::concat_cols(columns);
}

}  // namespace hnn::ad::testing
