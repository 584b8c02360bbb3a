#pragma once
// Fused ops for tanh MLPs, the models of the paper: one node for a whole network, computed in
// row blocks on the engine's threads (parallel.h) with hand-derived first-order backward passes
// that reuse the forward's intermediates (mlp_kernels.cpp). When a backward is itself recorded
// (create_graph), the same formulas are built from differentiable ops instead (mlp_recorded.cpp),
// so derivatives of any order still work; the two paths are tested against each other and
// against finite differences. Their tanh is ad::tanh's kernel: the same bits.
//
// The MLP: h_0 = x, h_i = tanh(h_{i-1} W_i + b_i) for i < L, y = h_{L-1} W_L (+ b_L).
// weights[i] is in x out; biases[i] is a 1 x out row or an undefined Var (no bias).

#include <vector>

#include "autodiff/var.h"

namespace hnn::ad {

/// y, R x out. d/dx, d/dW_i, d/db_i by backpropagation.
template <typename T>
Var<T> tanh_mlp(const Var<T>& x, const std::vector<Var<T>>& weights,
                const std::vector<Var<T>>& biases);

/// The gradient of the MLP's output with respect to its input, row by row: dy/dx, R x in (the
/// HNN's dH/dx). With m outputs, R x (m in): column block j is dy_j/dx (a D-HNN's dH/dx and
/// dD/dx in one op, sharing the forward pass and half the backward). Differentiable in x and
/// every parameter (this is the second-order path of HNN training); the last bias does not
/// affect it and is not an input. For one output of several alone, pass the column's slice of
/// the last weight (slice_cols(w, column, 1)).
template <typename T>
Var<T> tanh_mlp_input_gradient(const Var<T>& x, const std::vector<Var<T>>& weights,
                               const std::vector<Var<T>>& biases);

}  // namespace hnn::ad
