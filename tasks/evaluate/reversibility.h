#pragma once
// Reversibility of a learned model (the paper's section 6): integrate its field forward over a
// span and back again, and measure how far the states return from where they started; and the
// volume change of its flow map (Liouville: an HNN's flow keeps phase-space volume, det = 1).
// On any learned field: a task's state space or the pixel pendulum's latent space.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "physics/types.h"

namespace hnn::tasks {

struct ReversibilityOptions {
  /// midpoint is symmetric (its step undone by the negative step), so it returns to the start
  /// up to its solver tolerance for any field; rk4 and dopri5 are not, and show how the field
  /// itself amplifies their errors on the way back.
  std::vector<std::string> integrators = {"midpoint", "rk4", "dopri5"};
  double t_end = 0;    // 0: the task's rollout span (pixel: its rollout frames)
  double dt = 0;       // fixed-step methods; 0: t_end / 1000
  double rtol = 1e-9;  // dopri5
  int trajectories = 10;
};

/// Forward then backward from each row of x0 with each integrator; per integrator the mean and
/// max Euclidean return distance, its relative size (over |x0|), field calls and any failure;
/// and "volume": det of the flow map's Jacobian at each x0 (central differences, dopri5).
nlohmann::json measure_reversibility(const nn::DynamicsModel<double>& model,
                                     const physics::Batch& x0, const ReversibilityOptions& options);

}  // namespace hnn::tasks
