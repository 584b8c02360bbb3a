#include "nn/mlp.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <stdexcept>

#include "autodiff/grad.h"
#include "autodiff/mlp_ops.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::nn {

namespace {

void validate(const MlpConfig& config) {
  if (config.widths.size() < 2) {
    throw std::invalid_argument(
        fmt::format("Mlp: widths {} need at least an input and an output width", config.widths));
  }
  for (Index w : config.widths) {
    if (w < 1)
      throw std::invalid_argument(fmt::format("Mlp: widths {} must be >= 1", config.widths));
  }
}

// The fused op differentiates a single output: with several, it runs on the column's slice of the
// last weight (slice_cols is differentiable, so that column of the weight gets its gradient).
template <typename T>
ad::Var<T> fused_input_gradient(const ad::Var<T>& x, const std::vector<ad::Var<T>>& weights,
                                const std::vector<ad::Var<T>>& biases, Index column) {
  if (weights.back().cols() == 1) return ad::tanh_mlp_input_gradient(x, weights, biases);
  thread_local std::vector<ad::Var<T>> sliced;  // reused: no allocation per step
  sliced.assign(weights.begin(), weights.end());
  sliced.back() = ad::slice_cols(weights.back(), column, 1);
  const ad::Var<T> gradient = ad::tanh_mlp_input_gradient(x, sliced, biases);
  sliced.clear();  // release the parameters' handles (capacity stays)
  return gradient;
}

// Any activation, through the engine's double backpropagation. Training (grad mode on) keeps the
// derivative on the graph; under a NoGradGuard it is a value. Either way the forward pass must
// be recorded to be differentiated, on x itself when x requires gradients (so that a loss
// reaches whatever produced x) and on a variable copy on the tape otherwise.
template <typename T>
ad::Var<T> generic_input_gradient(const Mlp<T>& mlp, const ad::Var<T>& x, Index column) {
  const bool create_graph = ad::grad_enabled();
  ad::GradModeGuard record(true);
  const ad::Var<T> input = x.requires_grad() ? x : ad::Var<T>::variable(x.value());
  const ad::Var<T> out = mlp.forward(input);
  const ad::Var<T> y = out.cols() == 1 ? out : ad::slice_cols(out, column, 1);
  const ad::GradOptions options{.create_graph = create_graph, .allow_unused = true};
  thread_local std::vector<ad::Var<T>> inputs, gradient;  // reused: no allocation per step
  inputs.assign(1, input);
  ad::grad_into(ad::sum(y), inputs, gradient, options);
  const ad::Var<T> dx = gradient[0];
  inputs.clear();  // release the handles (capacity stays)
  gradient.clear();
  return dx;
}

}  // namespace

std::string describe(const MlpConfig& config) {
  return fmt::format("{} {} {}{}", fmt::join(config.widths, "-"), to_string(config.activation),
                     to_string(config.init), config.last_bias ? "" : " nobias");
}

template <typename T>
Mlp<T>::Mlp(MlpConfig config, std::mt19937_64& rng) : config_(std::move(config)) {
  validate(config_);
  const std::size_t n = config_.widths.size() - 1;
  layers_.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool bias = i + 1 < n || config_.last_bias;
    layers_.emplace_back(config_.widths[i], config_.widths[i + 1], rng, config_.init, bias);
  }
  collect_parameters();
}

template <typename T>
Mlp<T>::Mlp(MlpConfig config, std::vector<Linear<T>> layers)
    : config_(std::move(config)), layers_(std::move(layers)) {
  validate(config_);
  const std::size_t n = config_.widths.size() - 1;
  if (layers_.size() != n) {
    throw std::invalid_argument(
        fmt::format("Mlp: {} layers given for widths {}", layers_.size(), config_.widths));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Linear<T>& l = layers_[i];
    const bool bias = i + 1 < n || config_.last_bias;
    if (l.in_features() != config_.widths[i] || l.out_features() != config_.widths[i + 1] ||
        l.has_bias() != bias) {
      throw std::invalid_argument(
          fmt::format("Mlp: layer {} is {} -> {} ({} bias) but the config wants {} -> {} ({} bias)",
                      i, l.in_features(), l.out_features(), l.has_bias() ? "with" : "no",
                      config_.widths[i], config_.widths[i + 1], bias ? "with" : "no"));
    }
  }
  collect_parameters();
}

template <typename T>
void Mlp<T>::collect_parameters() {
  weights_.clear();
  biases_.clear();
  for (const Linear<T>& layer : layers_) {
    weights_.push_back(layer.weight());
    biases_.push_back(layer.bias());
  }
}

template <typename T>
ad::Var<T> Mlp<T>::forward(const ad::Var<T>& x) const {
  if (config_.activation == Activation::kTanh) return ad::tanh_mlp(x, weights_, biases_);
  ad::Var<T> h = layers_.front().forward(x);
  for (std::size_t i = 1; i < layers_.size(); ++i) {
    h = layers_[i].forward(activate(config_.activation, h));
  }
  return h;
}

template <typename T>
ad::Var<T> Mlp<T>::input_gradient(const ad::Var<T>& x, Index column) const {
  if (column < 0 || column >= output_dim()) {
    throw std::invalid_argument(fmt::format("Mlp::input_gradient: column {} of an MLP with {} {}",
                                            column, output_dim(),
                                            output_dim() == 1 ? "output" : "outputs"));
  }
  if (config_.activation == Activation::kTanh) {
    return fused_input_gradient(x, weights_, biases_, column);
  }
  return generic_input_gradient(*this, x, column);
}

template <typename T>
ad::Var<T> Mlp<T>::input_gradients(const ad::Var<T>& x) const {
  if (config_.activation == Activation::kTanh)
    return ad::tanh_mlp_input_gradient(x, weights_, biases_);
  if (output_dim() == 1) return generic_input_gradient(*this, x, 0);
  thread_local std::vector<ad::Var<T>> columns;  // reused: no allocation per step
  columns.clear();
  for (Index j = 0; j < output_dim(); ++j) columns.push_back(generic_input_gradient(*this, x, j));
  const ad::Var<T> all = ad::concat_cols(columns);
  columns.clear();  // release the handles (capacity stays)
  return all;
}

template <typename T>
void Mlp<T>::visit_parameters(const ParameterVisitor<T>& visit) {
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    visit_child<T>(layers_[i], fmt::format("layers.{}", i), visit);
  }
  collect_parameters();  // the visitor may have rebound them (bind_parameters)
}

template <typename T>
std::string Mlp<T>::kind() const {
  return fmt::format("mlp:{}", to_string(config_.activation));
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace hnn::nn
