#pragma once
// Optimisers with PyTorch's semantics. Their state (moments, momentum buffers) is plain
// matrices off the tape, allocated once; a step updates the parameter leaves in place through
// mutable_value() and allocates nothing.

#include <cstdint>
#include <vector>

#include "nn/module.h"

namespace hnn::nn {

/// Updates a fixed list of parameters (leaves) from their gradients.
template <typename T>
class Optimizer {
 public:
  explicit Optimizer(std::vector<ad::Var<T>> parameters);
  virtual ~Optimizer() = default;

  /// One update with `grads[i]` the gradient of parameters()[i] (e.g. from ad::grad(loss,
  /// parameters)). Sizes and shapes are checked before anything changes (std::invalid_argument).
  void step(const std::vector<ad::Var<T>>& grads);
  /// One update with the gradients accumulated in the leaves by ad::backward (zero if none).
  void step();
  /// Zeroes the leaves' accumulated gradients (for use with ad::backward).
  void zero_grad();

  const std::vector<ad::Var<T>>& parameters() const { return parameters_; }
  /// Steps taken so far.
  std::int64_t step_count() const { return steps_; }
  virtual double lr() const = 0;
  virtual void set_lr(double lr) = 0;

 protected:
  /// Updates parameter i with gradient g; steps_ already counts this step.
  virtual void update(std::size_t i, Matrix<T>& parameter, const Matrix<T>& g) = 0;

  std::vector<ad::Var<T>> parameters_;
  std::int64_t steps_ = 0;
};

/// torch.optim.Adam (amsgrad off), or torch.optim.AdamW with decoupled_weight_decay. Per step
/// t, for each parameter p with gradient g:
///   Adam:  g <- g + weight_decay p        (L2 added to the gradient, scaled as the loss's is)
///   AdamW: p <- p (1 - lr weight_decay)   (decay outside the moments, at the current lr)
///   m <- beta1 m + (1 - beta1) g,   v <- beta2 v + (1 - beta2) g^2
///   p <- p - lr / (1 - beta1^t) * m / (sqrt(v) / sqrt(1 - beta2^t) + eps)
/// i.e. p -= lr m_hat / (sqrt(v_hat) + eps), eps added after the square root. Scalar factors are
/// computed in double, the elementwise arithmetic in T.
struct AdamOptions {
  double lr = 1e-3;
  double beta1 = 0.9;
  double beta2 = 0.999;
  double eps = 1e-8;
  double weight_decay = 0;
  bool decoupled_weight_decay = false;  // AdamW (Loshchilov & Hutter 2019)
};

/// Parameters with their own Adam settings, as torch.optim.Adam's param_groups: e.g. weight decay
/// on some layers only.
template <typename T>
struct AdamGroup {
  std::vector<ad::Var<T>> parameters;
  AdamOptions options;
};

/// Everything an Adam carries between steps, for training checkpoints: the step count (which the
/// bias corrections use) and both moments of every parameter, in parameter order.
template <typename T>
struct AdamState {
  std::int64_t steps = 0;
  std::vector<Matrix<T>> m, v;
};

/// One group, or several (torch.optim.Adam(param_groups)): parameters() lists the groups'
/// parameters end to end, step(grads) takes their gradients in that order and updates each
/// parameter with its group's options, and every group shares the step count.
template <typename T>
class Adam : public Optimizer<T> {
 public:
  explicit Adam(std::vector<ad::Var<T>> parameters, AdamOptions options = {});
  /// At least one group; a parameter may be in one group only (std::invalid_argument).
  explicit Adam(const std::vector<AdamGroup<T>>& groups);

  std::size_t group_count() const { return options_.size(); }
  const AdamOptions& options(std::size_t group = 0) const { return options_.at(group); }
  /// The first group's learning rate.
  double lr() const override { return options_.front().lr; }
  /// Sets every group's learning rate.
  void set_lr(double lr) override;
  void set_lr(std::size_t group, double lr);
  /// m and v of parameter i.
  const Matrix<T>& first_moment(std::size_t i) const { return m_.at(i); }
  const Matrix<T>& second_moment(std::size_t i) const { return v_.at(i); }
  /// A copy of the step count and moments.
  AdamState<T> state() const { return {this->steps_, m_, v_}; }
  /// Restores a state() taken from an Adam over parameters of the same shapes, so the next step
  /// is bit for bit the one the original would take. Throws std::invalid_argument (naming the
  /// first mismatch) and changes nothing if the counts or shapes differ or steps < 0.
  void load_state(AdamState<T> state);

 protected:
  void update(std::size_t i, Matrix<T>& parameter, const Matrix<T>& g) override;

 private:
  std::vector<AdamOptions> options_;  // per group
  std::vector<std::size_t> group_;    // per parameter: its group
  std::vector<Matrix<T>> m_, v_;
};

/// torch.optim.SGD. For each parameter p with gradient g:
///   g <- g + weight_decay p
///   with momentum mu: b <- g on the first step, else mu b + (1 - dampening) g;
///                     g <- g + mu b (nesterov) or b
///   p <- p - lr g
struct SgdOptions {
  double lr = 1e-2;
  double momentum = 0;
  double dampening = 0;
  double weight_decay = 0;
  bool nesterov = false;
};

template <typename T>
class Sgd : public Optimizer<T> {
 public:
  explicit Sgd(std::vector<ad::Var<T>> parameters, SgdOptions options = {});

  const SgdOptions& options() const { return options_; }
  double lr() const override { return options_.lr; }
  void set_lr(double lr) override { options_.lr = lr; }
  const Matrix<T>& momentum_buffer(std::size_t i) const { return buffers_.at(i); }

 protected:
  void update(std::size_t i, Matrix<T>& parameter, const Matrix<T>& g) override;

 private:
  SgdOptions options_;
  std::vector<Matrix<T>> buffers_;
};

}  // namespace hnn::nn
