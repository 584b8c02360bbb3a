#pragma once
// The CHNN and CLNN of Finzi, Wang & Wilson 2020 ("Simplifying Hamiltonian and Lagrangian Neural
// Networks via Explicit Constraints"): in Cartesian coordinates the mass matrix is constant and
// known, so the MLP learns only the potential V(positions); the constraint forces come from
// multipliers solved per state (nn/constrained/mechanics.h). States are x = (positions,
// velocities) of config.constraints, both forms take and return (x, v) coordinates.

#include <random>

#include "nn/constrained/mechanics.h"
#include "nn/dynamics.h"

namespace hnn::nn {

/// config.model kChnn: the constrained Hamiltonian field (J dH projected onto the tangent space
/// of the constraints and their time derivative, H = 1/2 p^T M^-1 p + V, p = M v); kClnn: the
/// constrained Euler-Lagrange field. Parameters: "mlp.layers.<i>.weight|bias" of V's MLP.
template <typename T>
class ConstrainedModel : public DynamicsModel<T> {
 public:
  /// config.model must be kChnn or kClnn, with its constraints. Parameters initialised from rng.
  ConstrainedModel(DynamicsConfig config, std::mt19937_64& rng);
  /// A model with the given MLP, which must match mlp_config(config).
  ConstrainedModel(DynamicsConfig config, Mlp<T> mlp);
  ConstrainedModel(ConstrainedModel&&) noexcept = default;
  ConstrainedModel& operator=(ConstrainedModel&&) noexcept = default;

  /// The learned potential V(positions) of states x (R x dim), R x 1, on the tape.
  ad::Var<T> potential(const ad::Var<T>& x) const;
  /// The learned energy 1/2 v^T M v + V, R x 1: what the learned motion conserves.
  Matrix<T> energy(const Matrix<T>& x) const;

  /// (dpositions/dt, dvelocities/dt), R x dim, on the tape to any order (training differentiates
  /// through dV/dx, the Gram blocks and the solves). Throws ad::Error naming the row where the
  /// constraints are degenerate (a singular Gram block G M^-1 G^T).
  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;

  const ConstrainedMechanics<T>& mechanics() const { return mechanics_; }

  template <typename U>
  ConstrainedModel<U> cast() const {
    return ConstrainedModel<U>(this->config_, this->mlp_.template cast<U>());
  }

 private:
  ConstrainedMechanics<T> mechanics_;
};

}  // namespace hnn::nn
