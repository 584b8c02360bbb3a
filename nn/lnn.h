#pragma once
// The Lagrangian neural network (Cranmer et al. 2020): an MLP maps x = (q, v), v = dq/dt, to a
// learned Lagrangian L, and the motion follows from the Euler-Lagrange equations,
//   dv/dt = (d²L/dv²)⁻¹ (dL/dq - (d²L/dv dq) v),
// solved row by row. With config.kinetic_prior > 0, L = MLP(x~) + kinetic_prior · |v~|² / 2 on
// the MLP's scaled input x~ (DynamicsConfig::kinetic_prior says why). Training differentiates
// through the per-sample Hessian blocks and the solve, a third-order path through the MLP.

#include <random>

#include "nn/dynamics.h"

namespace hnn::nn {

template <typename T>
class Lnn : public DynamicsModel<T> {
 public:
  /// config.model must be kLnn. Parameters initialised from `rng`.
  Lnn(DynamicsConfig config, std::mt19937_64& rng);
  /// An LNN with the given MLP, which must match mlp_config(config).
  Lnn(DynamicsConfig config, Mlp<T> mlp);
  Lnn(Lnn&&) noexcept = default;
  Lnn& operator=(Lnn&&) noexcept = default;

  /// The learned Lagrangian L(q, v), R x 1, the prior term included.
  ad::Var<T> lagrangian(const ad::Var<T>& x) const;
  /// The learned energy E = v · dL/dv - L, R x 1: what the learned motion conserves.
  Matrix<T> energy(const MatrixView<T>& x) const;
  bool has_learned_energy() const override { return true; }
  Matrix<T> learned_energy(const MatrixView<T>& x) const override { return energy(x); }

  /// (v, dv/dt). Throws ad::Error naming the row when a block d²L/dv² is singular or
  /// ill-conditioned (the learned L has no well-defined motion there).
  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;

  template <typename U>
  Lnn<U> cast() const {
    return Lnn<U>(this->config_, this->mlp_.template cast<U>());
  }

 private:
  /// d(prior term)/dv = v · prior_slope_, a 1 x n row: kinetic_prior / scale_v².
  Matrix<T> prior_slope_;
};

}  // namespace hnn::nn
