// The peer's rollout metric for constrained systems (Finzi et al. 2020, pl_trainer.py and
// plot-relative-errors-v2.ipynb): relative state error in Cartesian (x, v), its geometric mean
// over time per trajectory and over trajectories, and the floor of a perturbed truth. Here in
// physics, beside the systems, so that tasks and the Python charts' callers share one definition
// without depending on the models.
#pragma once

#include <random>
#include <vector>

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

/// ||z_hat - z|| / (||z_hat|| + ||z||) for each row (Euclidean norms over all columns).
Eigen::VectorXd relative_errors(const Batch& predicted, const Batch& truth);

/// The peer's geometric mean over time of one trajectory's errors e_0..e_{K-1} at spacing dt:
/// exp(dt * trapz(log(e + 1e-8)) / horizon), with horizon its integration_time (so 100 outputs
/// at dt 0.03 over horizon 3, as the peer, divide 99 steps' integral by 3).
double trajectory_geometric_mean(const Eigen::VectorXd& errors, double dt, double horizon);

/// exp(mean(log v)).
double pooled_geometric_mean(const Eigen::VectorXd& values);

struct RolloutScore {
  /// Per trajectory (row): its geometric mean over time; NaN for a failed rollout.
  Eigen::VectorXd per_trajectory;
  /// pooled_geometric_mean over the rollouts that did not fail.
  double geometric_mean = 0.0;
  /// Rollouts with a non-finite predicted state at some time (counted, not pooled).
  int failed = 0;
};

/// Scores predicted against true states, both as Trajectory::states (one batch per time, rows =
/// trajectories, columns = Cartesian (x, v)), at the system's dt and horizon.
RolloutScore score_rollouts(const std::vector<Batch>& predicted, const std::vector<Batch>& truth,
                            double dt, double horizon);

/// How floor_score puts the perturbed start back on the manifold.
enum class FloorProjection {
  kPeer,          ///< ConstrainedSystem::project_peer, as the peer's compare_rollouts
  kMassWeighted,  ///< ConstrainedSystem::project
};

/// The floor: each start moved by eps N(0, 1) per component, projected back onto the manifold,
/// the truth integrated from it (simulate_constrained with `options`), and this perturbed truth
/// scored against the truth, which must be at system.output_times(). The projection changes the
/// floor (over 100 two-link chain starts: 6.0e-5 with the peer's, 8.5e-5 M-weighted; the peer
/// published 5.9e-5), so the peer's is the default. Returns the perturbed states too.
struct FloorResult {
  RolloutScore score;
  std::vector<Batch> perturbed;
};
FloorResult floor_score(const ConstrainedSystem& system, const Batch& z0,
                        const std::vector<Batch>& truth, std::mt19937_64& rng,
                        const TruthOptions& options = {}, double eps = 1e-4,
                        FloorProjection projection = FloorProjection::kPeer);

}  // namespace hnn::physics::constrained
