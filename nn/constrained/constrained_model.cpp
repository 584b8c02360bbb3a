#include "nn/constrained/constrained_model.h"

#include <fmt/format.h>

#include <stdexcept>

#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::nn {

namespace {

const DynamicsConfig& require_constrained(const DynamicsConfig& config) {
  if (!is_constrained(config.model)) {
    throw std::invalid_argument(fmt::format(
        "a chnn or clnn model cannot be built from a '{}' config", to_string(config.model)));
  }
  validate(config);
  return config;
}

}  // namespace

template <typename T>
ConstrainedModel<T>::ConstrainedModel(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require_constrained(config),
                       Mlp<T>(mlp_config(require_constrained(config)), rng)),
      mechanics_(config.constraints) {}

template <typename T>
ConstrainedModel<T>::ConstrainedModel(DynamicsConfig config, Mlp<T> mlp)
    : DynamicsModel<T>(require_constrained(config), std::move(mlp)),
      mechanics_(config.constraints) {}

template <typename T>
ad::Var<T> ConstrainedModel<T>::potential(const ad::Var<T>& x) const {
  this->check_input("potential", x.rows(), x.cols());
  return this->mlp_.forward(ad::slice_cols(x, 0, x.cols() / 2));
}

template <typename T>
Matrix<T> ConstrainedModel<T>::energy(const Matrix<T>& x) const {
  this->check_input("energy", x.rows(), x.cols());
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const Matrix<T> v = x.rightCols(x.cols() / 2);
  return (mechanics_.kinetic_energy(v) + potential(ad::Var<T>::constant(x)).value()).eval();
}

// dV/dx is the MLP's input gradient (one fused op for a tanh MLP), taken at the positions' slice
// of x, so a loss reaches x through it as well as through the mechanics.
template <typename T>
ad::Var<T> ConstrainedModel<T>::time_derivative(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const ad::Var<T> dv = this->mlp_.input_gradient(ad::slice_cols(x, 0, x.cols() / 2), 0);
  if (this->config_.model == ModelKind::kChnn) return mechanics_.hamiltonian_field(x, dv);
  return mechanics_.lagrangian_field(x, dv);
}

template class ConstrainedModel<float>;
template class ConstrainedModel<double>;

}  // namespace hnn::nn
