// AutodiffSystem: a Hamiltonian written in C++ with the autodiff engine's ops, H(q, p) over a
// batch of states, whose exact field (dH/dp, -dH/dq) comes from reverse-mode differentiation.
// Everything downstream of physics::System (integrators, datasets, training, rollouts) then
// works on a system the project does not ship, e.g. Hénon–Heiles:
//
//   physics::AutodiffSystem henon_heiles(
//       "henon-heiles", 2, [](const ad::Var<double>& q, const ad::Var<double>& p) {
//         const auto x = ad::slice_cols(q, 0, 1), y = ad::slice_cols(q, 1, 1);
//         return 0.5 * ad::sum_cols(ad::square(p) + ad::square(q)) + ad::square(x) * y -
//                ad::square(y) * y / 3.0;
//       });
#pragma once

#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "autodiff/var.h"
#include "physics/expression_system.h"  // ValueRange
#include "physics/system.h"

namespace hnn::physics {

/// H(q, p) written with the engine's ops (autodiff/ops.h). q and p are R x n (row i is state i:
/// its n coordinates, its n momenta); the result is the R x 1 column of H, one value per row.
/// Rows must be independent (H of row i may read row i only): the field differentiates the sum
/// of H over the batch. The callable may be called from several threads at once, each with its
/// own tape, and must not keep the Vars it is given.
using AutodiffHamiltonian =
    std::function<ad::Var<double>(const ad::Var<double>& q, const ad::Var<double>& p)>;

/// n initial states (n x 2n_dof, columns q then p), deterministic in rng.
using StateSampler = std::function<Batch(int n, std::mt19937_64& rng)>;

/// How an AutodiffSystem draws initial states when it has no StateSampler of its own: column j
/// uniform in box[j] ([-1, 1] each when box is empty), and with an energy band only the states
/// whose H lies in it (drawn from the box, the others rejected).
struct BoxSampling {
  std::vector<ValueRange> box{};  ///< one range per column (q_1..q_n, p_1..p_n), or none
  std::optional<ValueRange> energy{};
  long max_draws = 1'000'000;  ///< draws before giving up on filling the energy band
};

/// A System from H(q, p) in C++. hamiltonian_batch evaluates H; vector_field differentiates it
/// (one reverse sweep for the whole batch, inside its own TapeScope and with gradients on,
/// whatever the caller's grad mode), so the field is exact to rounding.
///
/// Bad input throws std::invalid_argument naming the system and what is wrong: n_dof < 1, an
/// empty name or callable, a box of the wrong size or with an empty or non-finite range, a bad
/// energy band; H returning an undefined Var or a shape other than R x 1 (found at construction,
/// from a probe of H on two zero states, and at every call); a batch whose column count is not
/// 2 n_dof; H or the field NaN or infinite at a state (named); a sampler returning the wrong
/// shape. An engine error inside H (ad::Error: mismatched shapes, ...) is rethrown as
/// std::invalid_argument naming the system.
class AutodiffSystem : public System {
 public:
  AutodiffSystem(std::string name, int n_dof, AutodiffHamiltonian hamiltonian,
                 BoxSampling sampling = {});
  AutodiffSystem(std::string name, int n_dof, AutodiffHamiltonian hamiltonian,
                 StateSampler sampler);

  int dim() const override { return 2 * n_dof_; }
  /// Degrees of freedom n (dim() / 2).
  int n_dof() const { return n_dof_; }
  std::string name() const override { return name_; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  /// (dH/dp, -dH/dq) row by row. Resizes dxdt if needed.
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// From the StateSampler, or as BoxSampling says; deterministic in rng. Throws
  /// std::invalid_argument when the energy band stays unfilled after max_draws.
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// H as given to the constructor.
  const AutodiffHamiltonian& hamiltonian_function() const { return hamiltonian_; }
  /// dH/dx = (dH/dq, dH/dp) for every row (R x dim), exact by reverse mode.
  Batch gradient(const BatchView& x) const;

 private:
  void check_columns(const BatchView& x) const;
  // H on the tape for q = x's first n columns and p = its last n; checks the shape.
  ad::Var<double> evaluate(const ad::Var<double>& q, const ad::Var<double>& p) const;
  // Throws naming the first state where `out` (H or the field, called `what`) is not finite.
  void check_finite(const BatchView& x, const Batch& out, const char* what) const;
  Batch sample_box(int n, std::mt19937_64& rng) const;

  std::string name_;
  int n_dof_;
  AutodiffHamiltonian hamiltonian_;
  StateSampler sampler_;
  BoxSampling sampling_;
};

}  // namespace hnn::physics
