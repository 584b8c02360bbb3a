#include "nn/constrained/constrained_model.h"

#include <fmt/format.h>

#include <stdexcept>

#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/constrained/masses.h"
#include "nn/init.h"

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

constexpr double kLogMassStd = 0.1;  // their d_moments: .1 * torch.randn

}  // namespace

template <typename T>
ConstrainedModel<T>::ConstrainedModel(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require_constrained(config),
                       Mlp<T>(mlp_config(require_constrained(config)), rng)),
      mechanics_(config.constraints) {
  if (mechanics_.mass_coefficients() > 0) {
    log_masses_ = ad::Var<T>::leaf(
        random_normal<T>(1, mechanics_.mass_coefficients(), rng, 0.0, kLogMassStd));
  }
}

template <typename T>
ConstrainedModel<T>::ConstrainedModel(DynamicsConfig config, Mlp<T> mlp, Matrix<T> log_masses)
    : DynamicsModel<T>(require_constrained(config), std::move(mlp)),
      mechanics_(config.constraints) {
  const Index k = mechanics_.mass_coefficients();
  if (log_masses.size() != k || (k > 0 && log_masses.rows() != 1)) {
    throw std::invalid_argument(fmt::format("constrained model: log masses {}x{} for {} learned",
                                            log_masses.rows(), log_masses.cols(), k));
  }
  if (k > 0) log_masses_ = ad::Var<T>::leaf(std::move(log_masses));
}

template <typename T>
typename ConstrainedMechanics<T>::MassOperators ConstrainedModel<T>::masses() const {
  if (!log_masses_.defined()) return mechanics_.known_masses();
  return mechanics_.learned_masses(ad::exp(-log_masses_));
}

template <typename T>
Matrix<T> ConstrainedModel<T>::inverse_mass_coefficients() const {
  if (log_masses_.defined()) return (-log_masses_.value()).array().exp().matrix();
  return nn::inverse_mass_coefficients(this->config_.constraints).transpose().template cast<T>();
}

template <typename T>
void ConstrainedModel<T>::visit_parameters(const ParameterVisitor<T>& visit) {
  DynamicsModel<T>::visit_parameters(visit);
  if (log_masses_.defined()) visit("log_masses", log_masses_);
}

template <typename T>
std::string ConstrainedModel<T>::describe() const {
  const std::string base = DynamicsModel<T>::describe();
  return log_masses_.defined() ? base + ", learned masses" : base;
}

template <typename T>
ad::Var<T> ConstrainedModel<T>::potential(const ad::Var<T>& x) const {
  this->check_input("potential", x.rows(), x.cols());
  return this->mlp_.forward(ad::slice_cols(x, 0, x.cols() / 2));
}

template <typename T>
Matrix<T> ConstrainedModel<T>::energy(const MatrixView<T>& x) const {
  this->check_input("energy", x.rows(), x.cols());
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const Matrix<T> v = x.rightCols(x.cols() / 2);
  const Matrix<T> kinetic =
      log_masses_.defined()
          ? mechanics_.kinetic_energy(v, mechanics_.mass_matrix(inverse_mass_coefficients()))
          : mechanics_.kinetic_energy(v, mechanics_.mass());
  return (kinetic + potential(ad::Var<T>::constant(x)).value()).eval();
}

// dV/dx is the MLP's input gradient (one fused op for a tanh MLP), taken at the positions' slice
// of x, so a loss reaches x through it as well as through the mechanics.
template <typename T>
ad::Var<T> ConstrainedModel<T>::time_derivative(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const ad::Var<T> dv = this->mlp_.input_gradient(ad::slice_cols(x, 0, x.cols() / 2), 0);
  if (this->config_.model == ModelKind::kChnn) return mechanics_.hamiltonian_field(x, dv, masses());
  return mechanics_.lagrangian_field(x, dv, masses());
}

template class ConstrainedModel<float>;
template class ConstrainedModel<double>;

}  // namespace hnn::nn
