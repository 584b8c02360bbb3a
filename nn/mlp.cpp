#include "nn/mlp.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <stdexcept>

#include "autodiff/mlp_ops.h"

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
ad::Var<T> Mlp<T>::input_gradient(const ad::Var<T>& x) const {
  if (!has_fused_input_gradient()) {
    throw std::logic_error(fmt::format(
        "Mlp::input_gradient: needs a tanh MLP with one output, not {}", describe(config_)));
  }
  return ad::tanh_mlp_input_gradient(x, weights_, biases_);
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
