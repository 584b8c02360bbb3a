// The planar double pendulum (point masses on massless rods) in angles and
// canonical momenta, for the measured double-pendulum data.
#pragma once

#include "physics/system.h"

namespace hnn::physics {

/// x = (theta1, theta2, p1, p2): angles from the downward vertical (theta2 is
/// absolute, not relative to rod 1) and their canonical momenta.
/// H = T(theta, p) + V(theta), zero at rest hanging down, where T = p^T M^-1 p / 2
/// with M = [[(m1+m2) l1^2, m2 l1 l2 c], [m2 l1 l2 c, m2 l2^2]], c = cos(theta1 - theta2),
/// and V = (m1+m2) g l1 (1 - cos theta1) + m2 g l2 (1 - cos theta2). Not separable.
class DoublePendulum : public System {
 public:
  /// Where V is zero: at rest hanging down (the default, above), or with the masses level with
  /// the pivot, V = -(m1+m2) g l1 cos theta1 - m2 g l2 cos theta2 (the sampled-HNN paper's code,
  /// hamiltonian/double_pendulum.py). The field is the same; H differs by a constant, which
  /// matters to an error relative to H's size.
  enum class PotentialZero { kAtRest, kAtPivot };

  DoublePendulum(double m1 = 1.0, double m2 = 1.0, double l1 = 1.0, double l2 = 1.0,
                 double g = 9.81, PotentialZero zero = PotentialZero::kAtRest);

  int dim() const override { return 4; }
  std::string name() const override { return "double_pendulum"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// Not in docs/tasks.md: angles U[-pi/2, pi/2], angular velocities U[-1, 1].
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// (theta1, theta2, omega1, omega2) rows -> (theta1, theta2, p1, p2): p = M omega.
  Batch momenta_from_velocities(const Batch& angles_and_velocities) const;
  /// The inverse: (theta1, theta2, p1, p2) -> (theta1, theta2, omega1, omega2).
  Batch velocities_from_momenta(const Batch& x) const;

  /// The constructor's arguments.
  struct Parameters {
    double m1, m2, l1, l2, g;
    PotentialZero zero;
  };
  Parameters parameters() const { return {m1_, m2_, l1_, l2_, g_, zero_}; }

 private:
  double m1_, m2_, l1_, l2_, g_;
  PotentialZero zero_;
};

/// The same double pendulum in angles and angular velocities x = (theta1, theta2, omega1,
/// omega2), as a Lagrangian NN learns it (Cranmer et al. 2020): dx/dt = (omega, alpha) from the
/// Euler-Lagrange equations, energy T + V as above (zero at rest). Not a canonical system:
/// hamiltonian_batch is the energy in these coordinates, and the field is not its symplectic
/// gradient.
class DoublePendulumVelocities : public System {
 public:
  /// g = 9.8 by default, as in the LNN paper's experiment (whose energy scale is 3 g = 29.4).
  DoublePendulumVelocities(double m1 = 1.0, double m2 = 1.0, double l1 = 1.0, double l2 = 1.0,
                           double g = 9.8);

  int dim() const override { return 4; }
  std::string name() const override { return "double_pendulum_velocities"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// The LNN paper's test states: angles U[0, 2 pi), angular velocities U[0, 0.1).
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;
  /// The canonical system of the same pendulum, for conversions.
  const DoublePendulum& canonical() const { return canonical_; }

 private:
  double m1_, m2_, l1_, l2_, g_;
  DoublePendulum canonical_;
};

}  // namespace hnn::physics
