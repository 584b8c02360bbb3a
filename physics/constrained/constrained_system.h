// Constrained systems of point masses in Cartesian coordinates (Finzi, Wang & Wilson 2020):
// a constant mass matrix, holonomic constraints, a potential; the exact field with its
// Lagrange multipliers, the energy, and the projection onto the constraint manifold.
#pragma once

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "physics/constrained/potentials.h"
#include "physics/integrator.h"
#include "physics/system.h"

namespace hnn::physics::constrained {

/// |x_i - x_j|^2 - length^2 = 0.
struct DistanceConstraint {
  int i = 0;
  int j = 0;
  double length = 1.0;
};

/// |x_i - anchor|^2 - length^2 = 0: a point tethered to a fixed point.
struct AnchorConstraint {
  int i = 0;
  Eigen::VectorXd anchor;
  double length = 1.0;
};

/// sum_j weights_j x_j - point = 0, one constraint per axis: a point fixed in a body (given by
/// affine weights over the body's points) held at a fixed point in space (a ball joint).
struct PinConstraint {
  Eigen::VectorXd weights;  ///< one per point of the system
  Eigen::VectorXd point;
};

class ConstrainedSystem;
/// n states on the constraint manifold, drawn as the peer's sample_initial_conditions.
using ConstrainedSampler =
    std::function<Batch(const ConstrainedSystem& system, int n, std::mt19937_64& rng)>;

/// Everything that defines a system, written once.
struct ConstrainedSpec {
  std::string name;
  int points = 0;
  int dim = 2;           ///< spatial dimension d (2 or 3)
  Eigen::MatrixXd mass;  ///< N x N, symmetric positive definite, acting on each axis alike
  std::vector<DistanceConstraint> distances;
  std::vector<AnchorConstraint> anchors;
  std::vector<PinConstraint> pins;
  Potential potential;
  ConstrainedSampler sampler;
  double dt = 0.1;       ///< the peer's time step between outputs
  double horizon = 1.0;  ///< the peer's integration_time: outputs at 0, dt, ... < horizon
};

/// One state's constraints linearised: phi(x) (C), J = dphi/dx (C x Nd), J v and
/// H = d(J v)/dx (C x Nd), so that d^2 phi/dt^2 = J a + H v.
struct Linearization {
  Eigen::VectorXd phi, jv;
  Eigen::MatrixXd jacobian, h;
};

/// A constrained system as a physics::System over z = (x, v): all positions then all
/// velocities, each point-major (x[i * d + k]), so dim() = 2 N d. Not canonical: hamiltonian_batch
/// is the energy v^T M v / 2 + V(x), and the field is the constrained Newtonian one.
class ConstrainedSystem : public System {
 public:
  explicit ConstrainedSystem(ConstrainedSpec spec);

  int dim() const override { return 2 * configuration_dim(); }
  std::string name() const override { return spec_.name; }
  const ConstrainedSpec& spec() const { return spec_; }
  int configuration_dim() const { return spec_.points * spec_.dim; }
  int constraint_count() const;
  /// kron(M, I_d) and its inverse, acting on the point-major position vector.
  const Eigen::MatrixXd& mass_full() const { return mass_full_; }
  const Eigen::MatrixXd& inverse_mass_full() const { return inverse_mass_full_; }
  /// The peer's output times: 0, dt, 2 dt, ... below horizon (100 of them for its systems).
  std::vector<double> output_times() const;

  Eigen::VectorXd hamiltonian_batch(const BatchView& z) const override;
  double potential(const double* x) const;
  Eigen::VectorXd potential_gradient(const double* x) const;

  /// The ground-truth field: the exact constrained dynamics written in the projected form of
  /// the peer's ConstrainedHamiltonianDynamics (see constrained_system.cpp), which equals
  /// (v, acceleration) on the manifold and keeps phi and d phi/dt constant off it.
  void vector_field(const BatchView& z, Batch& dzdt) const override;
  /// M a = -grad V - J^T lambda with lambda from (J M^-1 J^T) lambda = J M^-1 f + H v, the
  /// solve that keeps d^2 phi / dt^2 = 0. Rows x Nd.
  Batch acceleration(const Batch& z) const;
  /// The multipliers lambda of acceleration(), rows x C.
  Batch multipliers(const Batch& z) const;

  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  Linearization linearize(const double* x, const double* v) const;
  /// phi(x) for every row, rows x C.
  Batch constraint_values(const Batch& z) const;
  /// J(x) v for every row (d phi/dt), rows x C.
  Batch constraint_velocities(const Batch& z) const;

  /// Why state z (2 N d values: positions, then velocities) is off the manifold, in words that
  /// name the constraint ("points 0 and 1 are 0.9 apart, their rod is 1.08 long"); empty when
  /// every constraint holds to tol, relative to the rod's length (or the pivot's distance from
  /// the origin) for positions and to the points' relative speed for velocities.
  std::string state_problem(const double* z, double tol = 1e-6) const;
  /// Back onto the manifold: positions by Gauss-Newton steps of least M-norm
  /// (dx = -M^-1 J^T (J M^-1 J^T)^-1 phi) until |phi| < 1e-13 (1 + scale), then velocities
  /// M-orthogonally onto J v = 0. Throws std::runtime_error when 50 steps do not converge.
  Batch project(const Batch& z) const;
  /// The peer's project_onto_constraints: Gauss-Newton on (phi, J v) over the whole state in
  /// the Euclidean norm, each step clamped to half the batch's RMS, here to RMS violation
  /// below tol. Its samplers project with it. Throws std::runtime_error after 500 steps.
  Batch project_peer(const Batch& z, double tol = 1e-12) const;

 private:
  void add_distance_rows(const double* x, const double* v, Linearization& out, int& row) const;
  void add_pin_rows(const double* x, const double* v, Linearization& out, int& row) const;
  ConstrainedSpec spec_;
  Eigen::MatrixXd mass_full_, inverse_mass_full_;
};

/// Runs part(i) for every i in [0, parts), in any order and possibly on several threads at once:
/// how a caller with threads (the task layer, with the engine's) shares out the rows of a truth.
/// Empty: one after another, on the calling thread.
using RowParallel = std::function<void(int parts, const std::function<void(int)>& part)>;

/// How a truth is integrated: Dopri5's tolerances, and who runs its rows.
struct TruthOptions {
  double rtol = 1e-10, atol = 1e-12;
  RowParallel parallel{};
};

/// Ground truth: Dopri5 on the projected field at the options' tolerances, states at t_eval. Each
/// row is integrated on its own steps: in a shared batch the hardest row sets everyone's step (100
/// magnet-pendulum starts: 8,293 shared steps, 7x the time of one row at a time). The rows are
/// the parts of options.parallel; the states do not depend on how they are shared out.
Trajectory simulate_constrained(const ConstrainedSystem& system, const Batch& z0,
                                const std::vector<double>& t_eval,
                                const TruthOptions& options = {});

/// The peer's data states (RigidBodyDataset): n trajectories from the sampler at output_times(),
/// each cut into consecutive chunks of chunk_len outputs, one chunk kept per trajectory at random.
/// Its test starts are the first states of such chunks, not the sampled states: over 100 starts
/// the magnet pendulum's floor is 4.40e-4 from chunk starts and 6.3e-4 from sampled ones (the
/// peer published 4.45e-4).
struct ChunkSample {
  std::vector<Batch> states;      ///< chunk_len batches of n rows, dt apart
  std::vector<int> first_output;  ///< per row, the index in output_times() of its chunk's start
};
ChunkSample sample_chunks(const ConstrainedSystem& system, int n, int chunk_len,
                          std::mt19937_64& rng, const TruthOptions& options = {});

}  // namespace hnn::physics::constrained
