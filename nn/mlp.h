#pragma once
// The multilayer perceptron: Linear layers with an activation between them.

#include <random>
#include <vector>

#include "nn/activation.h"
#include "nn/init.h"
#include "nn/linear.h"

namespace hnn::nn {

/// Architecture of an MLP. The paper's: widths {in, 200, 200, out}, tanh, orthogonal weights,
/// last layer without bias.
struct MlpConfig {
  std::vector<Index> widths;  // input, hidden..., output: at least two entries, all >= 1
  Activation activation = Activation::kTanh;
  Init init = Init::kOrthogonal;
  bool last_bias = false;  // the hidden layers always have a bias
};

/// "2-200-200-1 tanh orthogonal nobias": for logs and reports.
std::string describe(const MlpConfig& config);

/// y = L_k(act(... act(L_1(x)))): the activation after every layer but the last.
/// Parameters: "layers.<i>.weight", "layers.<i>.bias".
template <typename T>
class Mlp : public Module<T> {
 public:
  /// Layers initialised in order from `rng`; throws std::invalid_argument on a bad config.
  Mlp(MlpConfig config, std::mt19937_64& rng);
  /// An MLP with the given layers, which must match the config's widths and biases.
  Mlp(MlpConfig config, std::vector<Linear<T>> layers);
  Mlp(Mlp&&) noexcept = default;
  Mlp& operator=(Mlp&&) noexcept = default;

  /// A tanh MLP runs as one fused op (ad::tanh_mlp); other activations layer by layer.
  ad::Var<T> forward(const ad::Var<T>& x) const;
  /// d y[:, column] / d x row by row (R x in: an HNN's dH/dx), differentiable in x and in every
  /// parameter, so a loss can be differentiated through it (the HNN's second-order path). A tanh
  /// MLP runs it as one fused op (ad::tanh_mlp_input_gradient, on the column's slice of the last
  /// weight when there are several outputs); other activations run ad::grad with create_graph.
  /// Throws std::invalid_argument for a column outside [0, output_dim()).
  ad::Var<T> input_gradient(const ad::Var<T>& x, Index column = 0) const;
  /// Every output's input gradient side by side: R x (out * in), column block j is
  /// d y[:, j] / dx (a D-HNN's dH/dx and dD/dx). A tanh MLP runs them as one fused op, which
  /// shares the forward pass and the way down of the backward between the outputs; other
  /// activations take input_gradient of each column.
  ad::Var<T> input_gradients(const ad::Var<T>& x) const;

  const MlpConfig& config() const { return config_; }
  const std::vector<Linear<T>>& layers() const { return layers_; }
  Index input_dim() const { return config_.widths.front(); }
  Index output_dim() const { return config_.widths.back(); }

  void visit_parameters(const ParameterVisitor<T>& visit) override;
  /// "mlp:<activation>".
  std::string kind() const override;

  /// A deep copy in scalar type U.
  template <typename U>
  Mlp<U> cast() const {
    std::vector<Linear<U>> layers;
    for (const Linear<T>& layer : layers_) layers.push_back(layer.template cast<U>());
    return Mlp<U>(config_, std::move(layers));
  }

 private:
  void collect_parameters();

  MlpConfig config_;
  std::vector<Linear<T>> layers_;
  std::vector<ad::Var<T>> weights_, biases_;  // handles of layers_' parameters, for fused ops
};

}  // namespace hnn::nn
