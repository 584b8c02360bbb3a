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
/// constrained Euler-Lagrange field. Parameters: "mlp.layers.<i>.weight|bias" of V's MLP, and
/// with config.constraints.learned_masses "log_masses" (1 x K): M^-1 = sum_k exp(-log_masses_k)
/// B_k (nn/constrained/masses.h), drawn as theirs, 0.1 N(0, 1) (masses near 1).
template <typename T>
class ConstrainedModel : public DynamicsModel<T> {
 public:
  /// config.model must be kChnn or kClnn, with its constraints. Parameters initialised from rng.
  ConstrainedModel(DynamicsConfig config, std::mt19937_64& rng);
  /// A model with the given MLP, which must match mlp_config(config), and log masses (1 x K;
  /// empty unless the config learns masses).
  ConstrainedModel(DynamicsConfig config, Mlp<T> mlp, Matrix<T> log_masses = {});
  ConstrainedModel(ConstrainedModel&&) noexcept = default;
  ConstrainedModel& operator=(ConstrainedModel&&) noexcept = default;

  /// The learned potential V(positions) of states x (R x dim), R x 1, on the tape.
  ad::Var<T> potential(const ad::Var<T>& x) const;
  /// The learned energy 1/2 v^T M v + V, R x 1: what the learned motion conserves.
  Matrix<T> energy(const MatrixView<T>& x) const;
  /// The same energy, as rollouts (their learned_h column) and `hnn hamiltonian` ask for it.
  bool has_learned_energy() const override { return true; }
  Matrix<T> learned_energy(const MatrixView<T>& x) const override { return energy(x); }

  /// (dpositions/dt, dvelocities/dt), R x dim, on the tape to any order (training differentiates
  /// through dV/dx, the Gram blocks and the solves). Throws ad::Error naming the row where the
  /// constraints are degenerate (a singular Gram block G M^-1 G^T).
  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;

  const ConstrainedMechanics<T>& mechanics() const { return mechanics_; }
  /// The inverse-mass coefficients c (1 x K) the model uses: learned, or the spec's true ones.
  Matrix<T> inverse_mass_coefficients() const;
  void visit_parameters(const ParameterVisitor<T>& visit) override;
  std::string describe() const override;

  template <typename U>
  ConstrainedModel<U> cast() const {
    return ConstrainedModel<U>(
        this->config_, this->mlp_.template cast<U>(),
        log_masses_.defined() ? log_masses_.value().template cast<U>() : Matrix<U>());
  }

 private:
  typename ConstrainedMechanics<T>::MassOperators masses() const;

  ConstrainedMechanics<T> mechanics_;
  ad::Var<T> log_masses_;  // a leaf when the masses are learned
};

}  // namespace hnn::nn
