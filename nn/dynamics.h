#pragma once
// The one interface every learned dynamics model offers (HNN and baseline alike), so that tasks,
// integrators and reports treat them the same way.

#include <string>
#include <string_view>
#include <vector>

#include "autodiff/tape.h"
#include "nn/constrained/constraints.h"
#include "nn/enum_names.h"
#include "nn/mlp.h"

namespace hnn::nn {

/// What a dynamics model learns.
enum class ModelKind {
  kHnn,       // a learned scalar; dx/dt from its derivatives (the field type below)
  kBaseline,  // an MLP that outputs dx/dt directly
  kDhnn,      // the dissipative HNN (Sosanya & Greydanus 2022): an HNN whose field type is kBoth
  kLnn,       // the Lagrangian NN (Cranmer et al. 2020): a learned L(q, v), x = (q, v = dq/dt)
  // Finzi, Wang & Wilson 2020, in Cartesian coordinates x = (positions, velocities) of a
  // DynamicsConfig::constraints system: a learned potential V(positions), the known mass matrix,
  // and the constraint forces from multipliers (nn/constrained/constrained_model.h).
  kChnn,  // the constrained Hamiltonian NN: J dH projected onto the constraints
  kClnn,  // the constrained Lagrangian NN: M a = -dV - DPhi^T lambda
  // Finzi et al.'s HNN (nn/mass_hnn.h): H = 1/2 p^T M^-1(q) p + V(q) with M^-1 and V learned,
  // on states x = (q, v = dq/dt), p = M(q) v.
  kMassHnn,
};

/// How an HNN turns learned scalars into a field (the reference's field_type).
enum class FieldType {
  kSolenoidal,    // (dH/dp, -dH/dq): conserves H, divergence-free: the HNN
  kConservative,  // dD/dx: a gradient field (dissipation) only
  kBoth,          // (dH/dp, -dH/dq) + dD/dx: the dissipative extension (friction)
};

/// Whether a model of this kind is an Hnn (learns H, and D, whose gradients give the field).
inline bool learns_scalars(ModelKind kind) {
  return kind == ModelKind::kHnn || kind == ModelKind::kDhnn;
}
/// Whether a model of this kind learns a potential of a constrained system (CHNN, CLNN).
inline bool is_constrained(ModelKind kind) {
  return kind == ModelKind::kChnn || kind == ModelKind::kClnn;
}
/// Whether the state's second half is velocities dq/dt (an LNN's, a mass HNN's), not canonical
/// momenta, of the task's own coordinates. (A CHNN's and a CLNN's are velocities too, but of the
/// Cartesian points of DynamicsConfig::constraints, which no task in generalised coordinates has.)
inline bool needs_velocities(ModelKind kind) {
  return kind == ModelKind::kLnn || kind == ModelKind::kMassHnn;
}

/// The names: "hnn", "baseline", "dhnn", "lnn", "chnn", "clnn", "hnn-mass"; "solenoidal",
/// "conservative", "both".
inline constexpr NameTable<ModelKind, 7> kModelKindNames{{
    {ModelKind::kHnn, "hnn"},
    {ModelKind::kBaseline, "baseline"},
    {ModelKind::kDhnn, "dhnn"},
    {ModelKind::kLnn, "lnn"},
    {ModelKind::kChnn, "chnn"},
    {ModelKind::kClnn, "clnn"},
    {ModelKind::kMassHnn, "hnn-mass"},
}};
inline constexpr NameTable<FieldType, 3> kFieldTypeNames{{
    {FieldType::kSolenoidal, "solenoidal"},
    {FieldType::kConservative, "conservative"},
    {FieldType::kBoth, "both"},
}};

std::string_view to_string(ModelKind kind);
std::string_view to_string(FieldType field);
/// Inverses of to_string; throw std::invalid_argument listing the valid names.
ModelKind parse_model_kind(std::string_view name);
FieldType parse_field_type(std::string_view name);

/// Everything that defines a dynamics model but its parameters. The defaults are the paper's
/// (docs/tasks.md): dim -> 200 -> 200 -> out, tanh, orthogonal, last layer without bias.
struct DynamicsConfig {
  ModelKind model = ModelKind::kHnn;
  Index dim = 2;  // state size 2n, x = (q_1..q_n, p_1..p_n); even for an HNN
  std::vector<Index> hidden = {200, 200};
  Activation activation = Activation::kTanh;
  Init init = Init::kOrthogonal;
  FieldType field = FieldType::kSolenoidal;  // HNN only; a kDhnn's must be kBoth
  /// The first `angles` coordinates are angles: the MLP sees each as (cos, sin), so a model is
  /// smooth and periodic in them. (A wrap to [-pi, pi) would be periodic but jump at +-pi, where
  /// a pendulum goes over the top: a learned energy would jump there too.)
  Index angles = 0;
  /// Empty, or one positive scale per coordinate: the MLP sees x / scale, so inputs of very
  /// different sizes (angular velocities of 10 beside angles of 1) do not saturate it.
  std::vector<double> input_scale{};
  /// LNN only: L = MLP(x~) + kinetic_prior · |v~|² / 2, where x~ is the MLP's input (scaled).
  /// The term gives d²L/dv² a positive part from the start, so the Euler-Lagrange solve is
  /// well-posed while the MLP is still random (a random MLP's blocks are near-singular at
  /// many states, and the loss there is enormous); the MLP learns the rest, and can cancel
  /// the term. 0: Cranmer et al.'s plain L = MLP.
  double kinetic_prior = 1.0;
  /// CHNN and CLNN only (empty for the others): the system, whose state x = (positions,
  /// velocities) has dim = 2 N d. Their MLP sees the positions only and learns V.
  ConstraintSpec constraints{};
  /// Baseline only: the state is (q, v = dq/dt) and the MLP outputs dv/dt alone, dq/dt = v being
  /// given, as the LNN paper's baseline does (Cranmer et al. 2020, their baseline_eom in
  /// notebooks/DoublePendulum-Baseline.ipynb). False: the MLP outputs all of dx/dt.
  bool given_velocities = false;
};

/// The MLP of a model: dim -> hidden... -> out, with out = dim for the baseline (dim / 2 with
/// given_velocities), the number of learned scalars for an HNN (1, or 2 for kBoth: column 0 is
/// H, column 1 is D), 1 (L) for an LNN; N d -> hidden... -> 1 (V of the positions) for a CHNN or
/// CLNN; dim / 2 (+ angles) -> hidden... -> 1 (V of q) for a mass HNN.
MlpConfig mlp_config(const DynamicsConfig& config);
/// Throws std::invalid_argument when the config cannot make a model (odd HNN dim, ...).
void validate(const DynamicsConfig& config);

/// A learned vector field dx/dt = f(x) on batches of states (rows).
template <typename T>
class DynamicsModel : public Module<T> {
 public:
  /// f(x) for a batch x (R x dim), on the graph when grad mode is on: the loss can then be
  /// differentiated through it (for an HNN, this is the second-order path). Works under a
  /// NoGradGuard too, giving values only.
  virtual ad::Var<T> time_derivative(const ad::Var<T>& x) const = 0;
  /// f(x) as plain values, for rollouts and evaluation: records only what it needs, inside its
  /// own TapeScope, whatever the grad mode. `x` is a view: a Matrix<T>, or a buffer laid out
  /// like one (apps/python/arrays.h passes a NumPy array's without copying it). By default
  /// time_derivative's values on a constant x under a NoGradGuard.
  virtual Matrix<T> field(const MatrixView<T>& x) const;
  /// Whether the model learns a quantity its motion conserves (an HNN's H, an LNN's energy
  /// v . dL/dv - L, a mass HNN's H, a CHNN's or CLNN's 1/2 v^T M v + V), and that quantity of
  /// states x, R x 1. The default learns
  /// none, and learned_energy then throws std::logic_error.
  virtual bool has_learned_energy() const { return false; }
  virtual Matrix<T> learned_energy(const MatrixView<T>& x) const;

  /// The state a fixed-step integrator carries (tasks/integrate/integrator_step.h) for states
  /// x as observed, its field, and the observed states of carried ones; all on the tape. For
  /// every model but the mass HNN the carried state is x itself and its field time_derivative.
  /// The mass HNN carries (q, p), solving p = M(q) v once at the start, as Finzi et al.'s
  /// HNN.integrate does: training through its steps then learns what theirs learns.
  virtual ad::Var<T> integrated_state(const ad::Var<T>& x) const { return x; }
  virtual ad::Var<T> integrated_derivative(const ad::Var<T>& z) const { return time_derivative(z); }
  virtual ad::Var<T> observed_state(const ad::Var<T>& z) const { return z; }
  /// integrated_derivative as plain values (the implicit midpoint's iterations): field(z) for
  /// every model but the mass HNN.
  virtual Matrix<T> integrated_field(const MatrixView<T>& z) const { return field(z); }

  const DynamicsConfig& config() const { return config_; }
  Index dim() const { return config_.dim; }
  const Mlp<T>& mlp() const { return mlp_; }
  /// "hnn", "hnn-conservative", "hnn-dissipative" (kBoth), "lnn", "chnn", "clnn" or "baseline".
  std::string name() const;
  /// name() + ":" + activation, e.g. "hnn:tanh": what checkpoints record and check.
  std::string kind() const override;
  /// "hnn 2-200-200-1 tanh orthogonal nobias", for logs.
  virtual std::string describe() const;
  /// Parameters: "mlp.layers.<i>.weight|bias".
  void visit_parameters(const ParameterVisitor<T>& visit) override;

 protected:
  DynamicsModel(DynamicsConfig config, Mlp<T> mlp);
  DynamicsModel(DynamicsModel&&) noexcept = default;
  DynamicsModel& operator=(DynamicsModel&&) noexcept = default;
  /// Throws ad::Error unless x is R x dim.
  void check_input(const char* what, Index rows, Index cols) const;
  /// The values of f(x) (a function of a Var, e.g. a member's time_derivative) for input x,
  /// checked as `what`, with nothing kept on the tape: field() and the like.
  template <typename F>
  Matrix<T> values_of(const char* what, const MatrixView<T>& x, const F& f) const {
    check_input(what, x.rows(), x.cols());
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    return f(ad::Var<T>::constant(x)).value();
  }
  /// What the MLP sees: x divided by the input scales, each angle coordinate as (cos, sin)
  /// (columns: cos of the angles, sin of the angles, the other coordinates); x itself when
  /// there are neither. On the tape, so derivatives of any order pass through.
  ad::Var<T> mlp_input(const ad::Var<T>& x) const;
  /// d mlp(mlp_input(x))[:, column] / dx: Mlp::input_gradient at the MLP's input, carried back
  /// through the (cos, sin) of the angles and the input scales (R x dim).
  ad::Var<T> input_gradient(const ad::Var<T>& x, Index column) const;
  /// input_gradient of every MLP output side by side, R x (outputs * dim) (Mlp::input_gradients).
  ad::Var<T> input_gradients(const ad::Var<T>& x) const;
  /// For MLPs of the positions q alone (the first half of a state, R x dim / 2): what the MLP
  /// sees of them (mlp_input's embedding), a gradient there carried back to q, and the tangent
  /// of the embedding along dq/dt = q_dot.
  ad::Var<T> position_input(const ad::Var<T>& q) const;
  ad::Var<T> position_gradient(const ad::Var<T>& q, const ad::Var<T>& g) const;
  ad::Var<T> position_tangent(const ad::Var<T>& q, const ad::Var<T>& q_dot) const;

  DynamicsConfig config_;
  Mlp<T> mlp_;
};

}  // namespace hnn::nn
