// The constrained systems that are not chains, in the generalised coordinates their peer's HNN
// learns them in (Finzi et al.'s body2globalCoords / global2bodyCoords): spherical angles per
// bob for the magnet and coupled pendulums, ZXZ Euler angles for the gyroscope, Euler angles and
// the centre for the rotor. The chains have their own, analytic twin (chain_angles.h).
#pragma once

#include <functional>
#include <string>

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

/// A state's Cartesian positions along a path q(s) = q + s u through the generalised
/// coordinates, to second order: x(q(s)) = x0 + s x1 + s^2 x2 (so x1 = J u and x2 = f''[u, u] / 2).
struct PositionJet {
  Eigen::VectorXd x0, x1, x2;
};

/// The map from generalised coordinates q (its first `angles` entries angles) to the points of a
/// constrained system, and back.
struct BodyMap {
  int dof = 0;
  int angles = 0;
  /// Positions (point-major, as ConstrainedSystem's) along q + s u.
  std::function<PositionJet(const Eigen::VectorXd& q, const Eigen::VectorXd& u)> positions;
  /// q of positions on the manifold, its angles in (-pi, pi] (the middle Euler angle in [0, pi]).
  std::function<Eigen::VectorXd(const double* x)> coordinates;
};

/// The system's map, for "coupled_pendulums_N", "magnet_pendulum", "gyroscope" and "rotor";
/// throws std::invalid_argument naming the system otherwise.
BodyMap body_map(const ConstrainedSystem& system);

/// The system in (q, dq/dt) rows, as a Lagrangian NN or the peer's HNN learns it. Its field is
/// the Cartesian system's mapped through the positions' Jacobian J: d^2q/dt^2 solves
/// J qddot = a - f''[qdot, qdot] by least squares (exact on the manifold, where J has full
/// column rank; not at a gimbal lock, where the coordinates themselves fail). Not canonical:
/// hamiltonian_batch is the energy.
class BodyCoordinates : public System {
 public:
  explicit BodyCoordinates(ConstrainedSystem cartesian);

  int dim() const override { return 2 * map_.dof; }
  std::string name() const override { return cartesian_.name() + "_body"; }
  /// How many leading coordinates are angles.
  int angles() const { return map_.angles; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// The Cartesian system's sampler mapped to (q, qdot).
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// (q, qdot) rows -> Cartesian (x, v) rows; with `curvature`, also each row's f''[qdot, qdot]
  /// (the positions' acceleration at qddot = 0), from the same pass.
  Batch to_cartesian(const BatchView& x, Batch* curvature = nullptr) const;
  /// Cartesian (x, v) rows on the manifold -> (q, qdot), qdot = J^+ v.
  Batch from_cartesian(const Batch& z) const;
  const ConstrainedSystem& cartesian() const { return cartesian_; }

 private:
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& q) const;

  ConstrainedSystem cartesian_;
  BodyMap map_;
};

}  // namespace hnn::physics::constrained
