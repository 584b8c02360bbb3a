// The constrained systems of Finzi, Wang & Wilson 2020 with their parameters, samplers, dt and
// horizon, read from mfinzi/constrained-hamiltonian-neural-networks (biases/systems/).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

/// A planar chain of point masses on massless rods from a pivot at the origin, gravity -y
/// (g = 9.81, V = g sum m_i y_i); dt 0.03, horizon 3. Sampler: link angles and rates N(0, 1),
/// mapped to (x, v), then positions + 0.2 N(0, 1) and velocities (v / 2 + 0.4 N(0, 1)) * 3,
/// projected back by project_peer (the peer's ChainPendulum.sample_initial_conditions).
ConstrainedSystem chain_pendulum(Eigen::VectorXd masses, Eigen::VectorXd lengths);
/// ChainPendulum(links) of the peer, links = 1..5: masses and lengths 0.6 + 0.8 U(0, 1) drawn
/// by numpy's seed 0 (masses first), the last drawn on the first link.
ConstrainedSystem chain_pendulum(int links);
/// The peer's masses and lengths of ChainPendulum(links), link 1 (at the pivot) first.
Eigen::VectorXd chain_pendulum_masses(int links);
Eigen::VectorXd chain_pendulum_lengths(int links);

/// CoupledPendulum(bobs): 3-D spherical pendulums of mass 1 and length 1 hung from (i, 0, 0),
/// neighbours joined by springs k = 10 of rest length 1, gravity -z; dt 0.05, horizon 5
/// (inherited from MagnetPendulum). Sampler: azimuth pi + 0.3 N, polar pi/2 + 0.3 N, both
/// rates 0.3 N per bob.
ConstrainedSystem coupled_pendulums(int bobs = 3);

/// MagnetPendulum(): a bob of mass 3 on a rod of length 1 from the origin, gravity -z, magnetic
/// moment q r / |r|^2 (q = 0.3) over two magnets of moment 0.3 z at (+-0.1, 0, -1.05);
/// dt 0.05, horizon 5. Sampler: azimuth pi + 0.3 N, its rate 0.05 N, polar pi/2 + 0.2 N, its
/// rate 0.4 N.
ConstrainedSystem magnet_pendulum();

/// Unit vector of the peer's spherical angles (azimuth phi, polar theta; the peer's rotated
/// frame): (-cos theta, sin phi sin theta, cos phi sin theta), and its time derivative.
void spherical_point(double phi, double theta, double phi_dot, double theta_dot, double* x,
                     double* v);

/// "chain_pendulum_1".."chain_pendulum_5", "coupled_pendulums_3", "magnet_pendulum",
/// "gyroscope", "rotor".
std::vector<std::string> constrained_system_names();
/// The system of that name; throws std::invalid_argument listing the names otherwise.
ConstrainedSystem make_constrained_system(const std::string& name);

}  // namespace hnn::physics::constrained
