#pragma once
// The HNN of Finzi, Wang & Wilson 2020 (their biases/models/hnn.py), the "HNN" of their tables:
// a Hamiltonian with the kinetic energy's structure built in,
//   H(q, p) = 1/2 p^T M^-1(q) p + V(q),   M^-1 = L L^T + eps I,
// where V and the lower-triangular factor L (a softplus on its diagonal, so M^-1 is positive
// definite) are MLPs of the positions. Like theirs it takes states as observed, x = (q, v =
// dq/dt), with p = M(q) v. Its field in those coordinates:
//   dq/dt = v,   dp/dt = -dH/dq (at fixed p),   dv/dt = M^-1 dp/dt + (dL L^T + L dL^T) p,
// where dL is the factor's tangent along the motion: one forward-mode pass of its MLP beside
// the reverse pass that dH/dq takes. Every piece is an engine op, so training differentiates
// through the field to any order.
//
// Training through fixed steps integrates (q, p) instead, as their HNN.integrate does: p = M v
// is solved for once per start, each stage is Hamilton's equations (no solve, no tangent pass)
// and each output reads v = M^-1 p. The two are the same motion but not the same RK4 steps: in
// (q, v) every stage solves with the stage's M^-1, which early in training may be nearly
// singular, and amplifies its error (docs/tasks.md, "Where their HNN fails").

#include <limits>
#include <random>
#include <vector>

#include "nn/dynamics.h"

namespace hnn::nn {

/// The diagonal eps of M^-1 = L L^T + eps I: theirs, which keeps M^-1 invertible however small
/// the learned factor.
inline constexpr double kMassHnnEpsilon = 1e-4;

/// The least rcond of M^-1 at which p = M v is solved: one epsilon, below which no digit of p is
/// left, instead of the engine's 100 (ad::kBatchedSolveMinRcond). Above it p is off by about
/// eps / rcond (6% at the rotor's 1.9e-6 in float), an error the loss of that start's chunk sees
/// and training moves away from; their float32 code solves at any conditioning, so a run stopped
/// there would be one theirs trains on. (The rotor's seed 2 stopped at step 1,262 on it.)
template <typename T>
inline constexpr double kMassHnnMinRcond = double(std::numeric_limits<T>::epsilon());

/// config.model kMassHnn, activation tanh. Parameters: "mlp.layers.<i>.weight|bias" of V's MLP,
/// "mass.layers.<i>.weight|bias" of L's.
template <typename T>
class MassHnn : public DynamicsModel<T> {
 public:
  /// Both MLPs initialised from `rng`, V's first; L's last bias starts at zero (as theirs).
  MassHnn(DynamicsConfig config, std::mt19937_64& rng);
  /// A model with the given MLPs: `potential` must match mlp_config(config), `mass`
  /// factor_mlp_config(config).
  MassHnn(DynamicsConfig config, Mlp<T> potential, Mlp<T> mass);
  MassHnn(MassHnn&&) noexcept = default;
  MassHnn& operator=(MassHnn&&) noexcept = default;

  /// The learned energy H = 1/2 p . v + V(q), R x 1: what the learned motion conserves.
  Matrix<T> energy(const MatrixView<T>& x) const;
  bool has_learned_energy() const override { return true; }
  Matrix<T> learned_energy(const MatrixView<T>& x) const override { return energy(x); }
  /// The learned M^-1(q) of states x (R x dim), each row an n x n block row-major.
  Matrix<T> inverse_mass(const MatrixView<T>& x) const;

  /// (v, dv/dt), on the tape to any order. Throws ad::Error naming the row where a learned
  /// M^-1 is not finite or too ill-conditioned to solve for p.
  ad::Var<T> time_derivative(const ad::Var<T>& x) const override;
  /// (q, p = M(q) v): what fixed-step integrators carry, as theirs. Throws as time_derivative.
  ad::Var<T> integrated_state(const ad::Var<T>& x) const override;
  /// Hamilton's equations in (q, p): dq/dt = M^-1 p, dp/dt = -dH/dq. No solve, no tangent pass.
  ad::Var<T> integrated_derivative(const ad::Var<T>& z) const override;
  /// (q, v = M^-1(q) p).
  ad::Var<T> observed_state(const ad::Var<T>& z) const override;
  /// integrated_derivative's values.
  Matrix<T> integrated_field(const MatrixView<T>& z) const override;

  /// "hnn-mass V 2-256-256-1, L 2-256-256-4 tanh orthogonal", for logs.
  std::string describe() const override;
  const Mlp<T>& factor_mlp() const { return factor_; }
  void visit_parameters(const ParameterVisitor<T>& visit) override;

  template <typename U>
  MassHnn<U> cast() const {
    return MassHnn<U>(this->config_, this->mlp_.template cast<U>(), factor_.template cast<U>());
  }

 private:
  struct Factor;                                // L and M^-1 of one batch
  Factor factor(const ad::Var<T>& raw) const;   // from the factor MLP's output
  Factor factor_at(const ad::Var<T>& q) const;  // L and M^-1 of positions q
  // dp/dt = -dH/dq at fixed momenta p, from the factor's pass at q (its MLP input `in`, its
  // hidden activations) and u = L^T p.
  ad::Var<T> momentum_rate(const ad::Var<T>& q, const ad::Var<T>& in,
                           const std::vector<ad::Var<T>>& hidden, const Factor& k,
                           const ad::Var<T>& p, const ad::Var<T>& u) const;
  void form_constants();

  Mlp<T> factor_;
  Matrix<T> strict_lower_, diagonal_;  // 1 x n^2 masks of L's entries
  Matrix<T> gram_;                     // n^4 x n^2: batched_outer(L, L) gram_ = L L^T
  Matrix<T> epsilon_;                  // 1 x n^2: eps I
};

/// The MLP of L: as mlp_config(config)'s, with n^2 outputs (L row-major) and a last bias.
MlpConfig factor_mlp_config(const DynamicsConfig& config);

}  // namespace hnn::nn
