// Hand-derived long-double derivatives of a tanh MLP: its input gradient and the parameter
// gradient of the HNN loss built on it (a second-order quantity: reverse over the input gradient).
#include "bench/accuracy/mlp_reference.h"

#include <stdexcept>

namespace hnn::accuracy {
namespace {

// Hidden activations h_0 = x, ..., h_{L-1} (one per layer; the output itself is not needed).
std::vector<LongMatrix> hidden_activations(const LongMlp& mlp, const LongMatrix& x) {
  std::vector<LongMatrix> h = {x};
  for (std::size_t i = 0; i + 1 < mlp.weights.size(); ++i) {
    LongMatrix a = h.back() * mlp.weights[i];
    if (mlp.biases[i].size() > 0) a.rowwise() += mlp.biases[i].row(0);
    h.push_back(a.array().tanh().matrix());
  }
  return h;
}

// 1 - h^2, the derivative of tanh at its output h.
LongMatrix tanh_slope(const LongMatrix& h) { return (1.0L - h.array().square()).matrix(); }

}  // namespace

LongMlp widen(const nn::Mlp<double>& mlp) {
  LongMlp out;
  for (const nn::Linear<double>& layer : mlp.layers()) {
    out.weights.push_back(layer.weight().value().cast<long double>());
    out.biases.push_back(layer.has_bias() ? LongMatrix(layer.bias().value().cast<long double>())
                                          : LongMatrix());
  }
  if (mlp.output_dim() != 1 || mlp.config().activation != nn::Activation::kTanh) {
    throw std::invalid_argument("mlp_reference: a tanh MLP with one output is needed");
  }
  return out;
}

LongMatrix input_gradient(const LongMlp& mlp, const LongMatrix& x) {
  const std::vector<LongMatrix> h = hidden_activations(mlp, x);
  const std::size_t last = mlp.weights.size() - 1;
  // d = dH/dh_i, from the top: dH/dh_{L-1} = W_{L-1}^T on every row.
  LongMatrix d = mlp.weights[last].transpose().replicate(x.rows(), 1);
  for (std::size_t i = last; i-- > 0;) {
    d = (d.array() * tanh_slope(h[i + 1]).array()).matrix() * mlp.weights[i].transpose();
  }
  return d;
}

LongLossGradient hnn_loss_gradient(const LongMlp& mlp, const LongMatrix& x,
                                   const LongMatrix& target) {
  const std::size_t layers = mlp.weights.size(), last = layers - 1;
  const Eigen::Index rows = x.rows(), dim = x.cols(), n = dim / 2;
  const std::vector<LongMatrix> h = hidden_activations(mlp, x);
  // Input gradient, keeping d_i = dH/dh_i and g_i = dH/da_i for the reverse pass.
  std::vector<LongMatrix> d(layers), g(last);
  d[last] = mlp.weights[last].transpose().replicate(rows, 1);
  for (std::size_t i = last; i-- > 0;) {
    g[i] = (d[i + 1].array() * tanh_slope(h[i + 1]).array()).matrix();
    d[i] = g[i] * mlp.weights[i].transpose();
  }
  LongMatrix field(rows, dim);  // F = (dH/dp, -dH/dq)
  field << d[0].rightCols(n), -d[0].leftCols(n);
  const LongMatrix residual = field - target;
  LongLossGradient out;
  out.loss = residual.array().square().sum() / static_cast<long double>(rows * dim);
  const LongMatrix field_bar = 2.0L * residual / static_cast<long double>(rows * dim);

  std::vector<LongMatrix> w_bar(layers), b_bar(layers), h_bar(layers);
  for (std::size_t i = 0; i < layers; ++i) {
    w_bar[i] = LongMatrix::Zero(mlp.weights[i].rows(), mlp.weights[i].cols());
    b_bar[i] = LongMatrix::Zero(mlp.biases[i].rows(), mlp.biases[i].cols());
  }
  // Reverse over the input gradient, bottom up: d_i = g_i W_i^T, g_i = d_{i+1} (1 - h_{i+1}^2).
  LongMatrix d_bar(rows, dim);
  d_bar << -field_bar.rightCols(n), field_bar.leftCols(n);
  for (std::size_t i = 0; i < last; ++i) {
    const LongMatrix g_bar = d_bar * mlp.weights[i];
    w_bar[i] += d_bar.transpose() * g[i];
    const LongMatrix slope = tanh_slope(h[i + 1]);
    h_bar[i + 1] = (g_bar.array() * d[i + 1].array() * (-2.0L) * h[i + 1].array()).matrix();
    d_bar = (g_bar.array() * slope.array()).matrix();
  }
  w_bar[last] += d_bar.colwise().sum().transpose();  // d_{L-1} = W_{L-1}^T on every row
  // Reverse over the forward pass, top down: h_{i+1} = tanh(h_i W_i + b_i).
  for (std::size_t i = last; i-- > 0;) {
    const LongMatrix a_bar = (h_bar[i + 1].array() * tanh_slope(h[i + 1]).array()).matrix();
    w_bar[i] += h[i].transpose() * a_bar;
    if (b_bar[i].size() > 0) b_bar[i] += a_bar.colwise().sum();
    if (i > 0) h_bar[i] += a_bar * mlp.weights[i].transpose();
  }
  for (std::size_t i = 0; i < layers; ++i) {
    out.gradients.push_back(w_bar[i]);
    if (b_bar[i].size() > 0) out.gradients.push_back(b_bar[i]);
  }
  return out;
}

}  // namespace hnn::accuracy
