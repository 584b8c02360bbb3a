#pragma once
// Internal: what the fused MLP ops (mlp_ops.h) share between their entry points, their hand-written
// kernels (mlp_kernels.cpp) and their recorded formulas (mlp_recorded.cpp): the layer layout the
// op stores on its node, a view of the layers over the op's inputs, and the kernels' signatures.
//
// Notation as in mlp_ops.h: L layers, hidden layers k = 1..L-1, h_0 = x.

#include <span>
#include <vector>

#include "autodiff/var.h"

namespace hnn::ad::detail {

/// The fused node's inputs are x, W_1..W_L, then the biases that exist, in layer order. Which
/// layers have a bias is the state the op keeps on its node (Node::state_for).
struct MlpLayout final : OpState {
  int layers = 0;
  std::vector<int> bias_input;  // [k - 1]: the input index of layer k's bias, or -1 for none

  /// The layout of `biases` (one entry per layer, undefined for none); with last_bias false the
  /// last layer's bias is left out. Reuses bias_input's storage.
  template <typename T>
  void set(const std::vector<Var<T>>& biases, bool last_bias) {
    layers = int(biases.size());
    bias_input.assign(biases.size(), -1);
    int next = 1 + layers;
    for (std::size_t i = 0; i < biases.size(); ++i) {
      if (biases[i].defined() && (i + 1 < biases.size() || last_bias)) bias_input[i] = next++;
    }
  }
};

/// The layers of a fused op, read from its inputs (the caller's Vars while the forward runs, the
/// node's inputs in its backward) and its layout. Layer i is in 1..L.
template <typename T>
struct MlpLayers {
  std::span<const Var<T>> inputs;
  const MlpLayout& layout;

  int count() const { return layout.layers; }
  /// The MLP's outputs (the last weight's columns).
  int outputs() const { return int(weight(count()).cols()); }
  int weight_input(int i) const { return i; }
  int bias_input(int i) const { return layout.bias_input[std::size_t(i - 1)]; }
  const Var<T>& x_var() const { return inputs[0]; }
  const Var<T>& weight(int i) const { return inputs[std::size_t(i)]; }
  const Var<T>* bias(int i) const {
    const int k = bias_input(i);
    return k < 0 ? nullptr : &inputs[std::size_t(k)];
  }
  const Matrix<T>& x() const { return x_var().value(); }
  const Matrix<T>& w(int i) const { return weight(i).value(); }
};

/// A fused node's layers, in its backward.
template <typename T>
MlpLayers<T> layers_of(const Node<T>& node) {
  return {node.inputs, node.template state_as<MlpLayout>()};
}

/// Where tanh_mlp_input_gradient keeps its intermediates in node.buffers: h_k for k = 1..L-1,
/// shared by the outputs, then a_k and d_k of every output column j (mlp_kernels.cpp defines a
/// and d).
struct GradientBuffers {
  int count;
  int columns = 1;
  std::size_t h(int k) const { return std::size_t(k - 1); }
  std::size_t a(int k, int j = 0) const { return std::size_t((count - 1) * (1 + j) + k - 1); }
  std::size_t d(int k, int j = 0) const {
    return std::size_t((count - 1) * (1 + columns + j) + k - 1);
  }
  std::size_t size() const { return std::size_t((count - 1) * (1 + 2 * columns)); }
};

// ---- the hand-written kernels (mlp_kernels.cpp): values only, threaded over row blocks -------

/// y into node.value; the hidden layers' h_k into node.buffers (for the backward).
template <typename T>
void tanh_mlp_forward(const MlpLayers<T>& l, Node<T>& node);
/// dy/dx into node.value; h, a and d into node.buffers as GradientBuffers says.
template <typename T>
void input_gradient_forward(const MlpLayers<T>& l, Node<T>& node);
/// First-order backward passes that reuse the forward's buffers.
template <typename T>
void tanh_mlp_backward_kernel(const Node<T>& node, const Var<T>& g, GradSink<T>& s);
template <typename T>
void input_gradient_backward_kernel(const Node<T>& node, const Var<T>& g, GradSink<T>& s);

// ---- the recorded formulas (mlp_recorded.cpp): the same backward passes in differentiable ops --

template <typename T>
void tanh_mlp_backward_recorded(const MlpLayers<T>& l, const Var<T>& g, GradSink<T>& s);
template <typename T>
void input_gradient_backward_recorded(const MlpLayers<T>& l, const Var<T>& g, GradSink<T>& s);

}  // namespace hnn::ad::detail
