// The planar N-link chain pendulum in angle coordinates, the twin of the Cartesian
// chain_pendulum (systems.h) for the HNN/LNN comparison, and the maps between the two.
#pragma once

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

/// Rows (theta_1..theta_N, omega_1..omega_N), angles of each link from the downward vertical
/// (absolute, not relative), -> rows (x, v) of the Cartesian chain from a pivot at the origin:
/// x_k = sum_{a <= k} l_a (sin theta_a, -cos theta_a), v_k its time derivative.
Batch chain_cartesian(const Eigen::VectorXd& lengths, const Batch& angles_and_rates);
/// The inverse, for states on the manifold: theta_k = atan2(r_x, -r_y) in (-pi, pi] and
/// omega_k = (r x u) / |r|^2, with r, u link k's relative position and velocity.
Batch chain_angles(int links, const Batch& cartesian);

/// Makes the angle columns (0..links-1) of each row continuous along time, in place: each
/// step's jump is brought into (-pi, pi] by whole turns, so chunks of a trajectory that crosses
/// theta = pi carry no 2 pi jumps (chain_angles returns angles in (-pi, pi]).
void unwrap_angles(std::vector<Batch>& states, int links);

/// x = (theta, p) with canonical momenta p = M(theta) omega, where
/// M_ab = mu_ab l_a l_b cos(theta_a - theta_b), mu_ab = sum_{k >= max(a, b)} m_k;
/// H = p^T M^-1 p / 2 - g sum_k m_k sum_{a <= k} l_a cos theta_a, the Cartesian chain's energy
/// (zero at the pivot's height). Not separable.
class ChainPendulumAngles : public System {
 public:
  ChainPendulumAngles(Eigen::VectorXd masses, Eigen::VectorXd lengths, double g = 9.81);
  /// The peer's ChainPendulum(links) parameters (systems.h).
  explicit ChainPendulumAngles(int links);

  int dim() const override { return 2 * links(); }
  std::string name() const override { return cartesian_.name() + "_angles"; }
  int links() const { return static_cast<int>(masses_.size()); }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// The Cartesian chain's sampler mapped to (theta, p): the same distribution of states.
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// M(theta) for one state.
  Eigen::MatrixXd mass_matrix(const Eigen::VectorXd& theta) const;
  /// dp/dt = -dH/dtheta at (theta, omega = M^-1 p).
  Eigen::VectorXd momentum_rate(const Eigen::VectorXd& theta, const Eigen::VectorXd& omega) const;
  /// d omega/dt, the Euler-Lagrange equations solved for the accelerations.
  Eigen::VectorXd angular_acceleration(const Eigen::VectorXd& theta,
                                       const Eigen::VectorXd& omega) const;
  const Eigen::VectorXd& lengths() const { return lengths_; }
  Batch momenta_from_velocities(const Batch& angles_and_rates) const;
  Batch velocities_from_momenta(const Batch& x) const;
  /// (theta, p) rows -> Cartesian (x, v) rows, to measure angle models in the Cartesian metric.
  Batch to_cartesian(const Batch& x) const;
  /// Cartesian (x, v) rows on the manifold -> (theta, p).
  Batch from_cartesian(const Batch& z) const;
  /// The same chain in Cartesian coordinates.
  const ConstrainedSystem& cartesian() const { return cartesian_; }

 private:
  Eigen::VectorXd masses_, lengths_;
  double g_;
  ConstrainedSystem cartesian_;
};

/// The same chain in angles and angular velocities x = (theta, omega), as a Lagrangian NN learns
/// it (like DoublePendulumVelocities): dx/dt = (omega, angular_acceleration). Not canonical:
/// hamiltonian_batch is the energy.
class ChainPendulumVelocities : public System {
 public:
  explicit ChainPendulumVelocities(ChainPendulumAngles canonical);
  explicit ChainPendulumVelocities(int links)
      : ChainPendulumVelocities(ChainPendulumAngles(links)) {}

  int dim() const override { return canonical_.dim(); }
  std::string name() const override { return canonical_.cartesian().name() + "_velocities"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// The Cartesian chain's sampler mapped to (theta, omega).
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;
  /// (theta, omega) rows -> Cartesian (x, v) rows.
  Batch to_cartesian(const Batch& x) const;
  const ChainPendulumAngles& canonical() const { return canonical_; }

 private:
  ChainPendulumAngles canonical_;
};

}  // namespace hnn::physics::constrained
