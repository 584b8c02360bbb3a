#pragma once
// The models: the Hamiltonian neural network (and its conservative / dissipative field types)
// and the baseline MLP, behind the DynamicsModel interface; a factory and float/double casts.

#include <memory>
#include <random>

#include "nn/dynamics.h"

namespace hnn::nn {

/// An HNN: an MLP maps x = (q, p) to learned scalars, and the field is built from their
/// gradients (see FieldType): the solenoidal part (dH/dp, -dH/dq) from dH/dx, the conservative
/// part dD/dx, each one Mlp::input_gradient (a fused op for a tanh MLP, ad::grad with
/// create_graph otherwise), differentiable in x too, so a loss can reach an encoder that
/// produced x.
template <typename T>
class Hnn : public DynamicsModel<T> {
 public:
  /// The two parts of the field; a part the field type lacks is undefined.
  struct Parts {
    ad::Var<T> solenoidal;    // (dH/dp, -dH/dq)
    ad::Var<T> conservative;  // dD/dx
  };

  /// config.model must be kHnn or kDhnn. Parameters initialised from `rng`.
  Hnn(DynamicsConfig config, std::mt19937_64& rng);
  /// An HNN with the given MLP, which must match mlp_config(config).
  Hnn(DynamicsConfig config, Mlp<T> mlp);
  Hnn(Hnn&&) noexcept = default;
  Hnn& operator=(Hnn&&) noexcept = default;

  /// The learned Hamiltonian H(x), R x 1 (the MLP's column 0); throws for kConservative.
  ad::Var<T> energy(const ad::Var<T>& x) const;
  Matrix<T> energy(const MatrixView<T>& x) const;
  /// H, for every field type but kConservative (which learns D alone).
  bool has_learned_energy() const override {
    return this->config_.field != FieldType::kConservative;
  }
  Matrix<T> learned_energy(const MatrixView<T>& x) const override { return energy(x); }
  /// The learned dissipation potential D(x), R x 1; throws for kSolenoidal.
  ad::Var<T> dissipation(const ad::Var<T>& x) const;

  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;
  /// Both parts separately (their sum is time_derivative).
  Parts time_derivative_parts(const ad::Var<T>& x) const;
  Matrix<T> field(const MatrixView<T>& x) const override;

  template <typename U>
  Hnn<U> cast() const {
    return Hnn<U>(this->config_, this->mlp_.template cast<U>());
  }
};

/// The paper's baseline: an MLP dim -> hidden... -> dim that outputs dx/dt directly (or dv/dt
/// alone, with DynamicsConfig::given_velocities).
template <typename T>
class Baseline : public DynamicsModel<T> {
 public:
  /// config.model must be kBaseline.
  Baseline(DynamicsConfig config, std::mt19937_64& rng);
  Baseline(DynamicsConfig config, Mlp<T> mlp);
  Baseline(Baseline&&) noexcept = default;
  Baseline& operator=(Baseline&&) noexcept = default;

  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;

  template <typename U>
  Baseline<U> cast() const {
    return Baseline<U>(this->config_, this->mlp_.template cast<U>());
  }
};

/// An Hnn, Lnn, ConstrainedModel (chnn, clnn), MassHnn or Baseline, as config.model says,
/// initialised from `rng`.
template <typename T>
std::unique_ptr<DynamicsModel<T>> make_model(const DynamicsConfig& config, std::mt19937_64& rng);

/// A deep copy of `model` in scalar type U (U = T: an independent clone).
template <typename U, typename T>
std::unique_ptr<DynamicsModel<U>> cast_model(const DynamicsModel<T>& model);

}  // namespace hnn::nn
