// Potentials of constrained point-mass systems in Cartesian coordinates: gravity, springs
// between points and the magnet pendulum's dipoles, each a term of V(x) with its gradient.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace hnn::physics::constrained {

/// One term of V(x). x holds one state's positions, point-major: x[i * d + k] is axis k of
/// point i (N points in d dimensions).
class PotentialTerm {
 public:
  virtual ~PotentialTerm() = default;
  virtual double value(const double* x) const = 0;
  /// Adds dV/dx to grad (N * d values).
  virtual void add_gradient(const double* x, double* grad) const = 0;
};

using Potential = std::vector<std::shared_ptr<const PotentialTerm>>;

/// V = g sum_i w_i x_i[axis]: uniform gravity along +axis (height), with w the column sums of
/// the mass matrix (for point masses, the masses; for a rigid body, its mass on the centre).
std::shared_ptr<const PotentialTerm> gravity(Eigen::VectorXd weights, int dim, int axis,
                                             double g = 9.81);

/// V = sum_c k_c (|x_i - x_j| - rest_c)^2 / 2 over the springs c = (i, j).
struct Spring {
  int i = 0;
  int j = 0;
  double stiffness = 0.0;
  double rest = 0.0;
};
std::shared_ptr<const PotentialTerm> springs(std::vector<Spring> list, int dim);

/// The magnet pendulum's dipole energy (3-D, one point r0): the bob carries the moment
/// m0 = q r0 / |r0|^2 and each fixed magnet i at r_i the moment m_i; with s = r_i - r0,
/// V = sum_i (-3 (m0.s)(m_i.s) - |s|^2 (m0.m_i)) / (4 pi |s|^5), as the peer's
/// MagnetPendulum.potential (biases/systems/magnet_pendulum.py). Gradient by forward-mode
/// differentiation of the same formula.
std::shared_ptr<const PotentialTerm> magnet_dipoles(double q, Eigen::MatrixXd positions,
                                                    Eigen::MatrixXd moments);

}  // namespace hnn::physics::constrained
