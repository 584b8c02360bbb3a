#pragma once
// Reference derivatives of a tanh MLP with one output (an HNN's learned H), written out by hand
// in long double and independent of the engine: what the finite-difference chart measures the
// errors of finite differences and of autodiff against.
//
// MLP: h_0 = x, h_{i+1} = tanh(h_i W_i + b_i) for the hidden layers, H = h_{L-1} W_{L-1} (+ b).

#include <Eigen/Core>
#include <vector>

#include "nn/mlp.h"

namespace hnn::accuracy {

using LongMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;

/// The layers' weights (in x out) and biases (1 x out, or 0 x 0 without a bias).
struct LongMlp {
  std::vector<LongMatrix> weights, biases;
};

/// The MLP's parameters, widened to long double (exactly).
LongMlp widen(const nn::Mlp<double>& mlp);

/// dH/dx row by row (R x in).
LongMatrix input_gradient(const LongMlp& mlp, const LongMatrix& x);

/// The HNN loss mean((F - target)^2) over all elements, F = (dH/dp, -dH/dq), and its gradient
/// with respect to every parameter: one matrix per parameter in the order of
/// nn::Module::parameters() (weight, then bias, per layer; the last layer's bias, if any, gets
/// zeros since F does not depend on it).
struct LongLossGradient {
  long double loss = 0;
  std::vector<LongMatrix> gradients;
};
LongLossGradient hnn_loss_gradient(const LongMlp& mlp, const LongMatrix& x,
                                   const LongMatrix& target);

}  // namespace hnn::accuracy
