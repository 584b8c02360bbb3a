// Planar N-body gravity (tasks 4 and 4b): H, field, conserved quantities and
// the two- and three-body initial-state samplers of docs/tasks.md.
#pragma once

#include <vector>

#include "physics/system.h"

namespace hnn::physics {

/// H = sum_i |p_i|^2 / (2 m_i) - sum_{i<j} G m_i m_j / |q_i - q_j|, in the
/// coordinate order (qx_1..qx_N, qy_1..qy_N, px_1..px_N, py_1..py_N).
class NBody : public SeparableSystem {
 public:
  /// Throws std::invalid_argument unless there are >= 2 positive masses and G > 0.
  explicit NBody(std::vector<double> masses, double gravity = 1.0);
  /// N bodies of mass 1 and G = 1, as in tasks 4 and 4b.
  static NBody equal_masses(int bodies);

  int bodies() const { return static_cast<int>(masses_.size()); }
  const std::vector<double>& masses() const { return masses_; }
  double gravity() const { return gravity_; }

  int dim() const override { return 4 * bodies(); }
  std::string name() const override;
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void velocity(const BatchView& p, BatchSpan dq) const override;
  void force(const BatchView& q, BatchSpan dp) const override;
  /// Two bodies: docs/tasks.md's near-circular orbits; three bodies: its perturbed
  /// rotating triangles. Other N: not specified, throws std::logic_error.
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// Total momentum (Px, Py) per row: rows x 2.
  Eigen::MatrixXd total_momentum(const Batch& x) const;
  /// Total angular momentum about the origin, sum_i (qx_i py_i - qy_i px_i).
  Eigen::VectorXd angular_momentum(const Batch& x) const;
  /// Centre of mass (X, Y) per row: rows x 2.
  Eigen::MatrixXd center_of_mass(const Batch& x) const;

  /// Column of a coordinate: axis 0 = x, 1 = y; momentum selects p over q.
  int column(int body, int axis, bool momentum) const;

 private:
  Batch sample_two_body(int n, std::mt19937_64& rng) const;
  Batch sample_three_body(int n, std::mt19937_64& rng) const;

  std::vector<double> masses_;
  double gravity_;
};

}  // namespace hnn::physics
