// The System interface (a Hamiltonian with its exact field, energy and initial
// states) and SeparableSystem for H = T(p) + V(q), which splitting methods use.
#pragma once

#include <optional>
#include <random>
#include <string>
#include <vector>

#include "physics/types.h"

namespace hnn::physics {

/// The two halves of a separable field, each given the whole state x = (q, p)
/// and writing rows x dim/2: drift = dq/dt = dT/dp (depends on p only) and
/// kick = dp/dt = -dV/dq (depends on q only).
struct SplitField {
  std::function<void(double t, const Batch& x, Batch& dq)> drift;
  std::function<void(double t, const Batch& x, Batch& dp)> kick;
};

/// A Hamiltonian system in canonical coordinates x = (q, p). Implementations
/// write each formula once, vectorised over the rows of a Batch.
class System {
 public:
  virtual ~System() = default;

  /// Phase-space dimension (2 x degrees of freedom).
  virtual int dim() const = 0;
  virtual std::string name() const = 0;

  /// H for every row of x. x is a view (BatchView): a Batch, a block of one, or rows of memory
  /// laid out like one, such as a NumPy array's buffer (apps/python/arrays.h), read in place.
  virtual Eigen::VectorXd hamiltonian_batch(const BatchView& x) const = 0;
  /// H at one state.
  double hamiltonian(const Eigen::Ref<const Eigen::RowVectorXd>& x) const;

  /// The exact field dx/dt = (dH/dp, -dH/dq), row by row; x a view as above. Resizes dxdt if
  /// needed.
  virtual void vector_field(const BatchView& x, Batch& dxdt) const = 0;

  /// The energy used in metrics: H itself for the conservative systems here.
  virtual Eigen::VectorXd energy_batch(const Batch& x) const { return hamiltonian_batch(x); }
  double energy(const Eigen::Ref<const Eigen::RowVectorXd>& x) const;

  /// n initial states drawn as docs/tasks.md specifies for this system.
  virtual Batch sample_initial_states(int n, std::mt19937_64& rng) const = 0;

  /// The state after time t from each row of x0, when a closed form exists.
  virtual std::optional<Batch> exact_flow(const Batch& x0, double t) const;

  /// The field as a callable for integrators. It refers to *this: keep the
  /// system alive while the callable is in use. Throws std::invalid_argument on
  /// a batch whose column count is not dim().
  VectorField field() const;

  /// The exact halves of the field when H = T(p) + V(q), for splitting methods; nullopt when
  /// H is not separable (the default). Refers to *this, like field().
  virtual std::optional<SplitField> separable_split() const { return std::nullopt; }
};

/// n states drawn uniformly in a box: column j uniform in box[j], drawn row by row (each row's
/// columns in order), so a seed gives the same states whatever n is for the rows they share.
Batch sample_box(int n, const std::vector<ValueRange>& box, std::mt19937_64& rng);

/// Splits a general field by evaluating it in full and keeping one half. Right
/// only when the field is separable; each half costs one full evaluation.
SplitField split_field(const VectorField& f);

/// H = T(p) + V(q): the two gradients separately, on views of the q or p block.
class SeparableSystem : public System {
 public:
  /// dq/dt = dT/dp from the momenta p (rows x dim/2).
  virtual void velocity(const BatchView& p, BatchSpan dq) const = 0;
  /// dp/dt = -dV/dq from the positions q (rows x dim/2).
  virtual void force(const BatchView& q, BatchSpan dp) const = 0;

  /// Assembled from velocity() and force().
  void vector_field(const BatchView& x, Batch& dxdt) const override;

  /// Exact halves for splitting integrators (each half costs only its own work).
  /// Refers to *this, like field().
  SplitField split() const;
  std::optional<SplitField> separable_split() const override { return split(); }
};

}  // namespace hnn::physics
