#pragma once
// Rollouts of the true and learned fields from the same initial states (or along measured paths),
// for the metrics (energy_errors.h, state_errors.h) and the charts. Losses over a split:
// loss_stats.h.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "physics/system.h"

namespace hnn::tasks {

using physics::Batch;

/// The evaluation's rollouts per run unless a task's data cannot give that many distinct initial
/// states (the HNN paper's Table 1 used 15), and the most a run may ask for.
constexpr int kDefaultRollouts = 100;
constexpr int kMaxRollouts = 1000;
/// The floor's perturbation: Finzi et al.'s 1e-4 (N(0, 1e-4^2) per component of the start).
constexpr double kFloorPerturbation = 1e-4;
/// A learned rollout taking more adaptive steps than this is reported as failed (with the time
/// reached) rather than left to run for hours: a badly trained field can be stiff enough to need
/// the integrator's default limit of 1e8 steps. True fields keep that default.
constexpr long kMaxLearnedSteps = 100'000;

/// How rollouts for the energy metric are made.
struct RolloutConfig {
  int trajectories = kDefaultRollouts;
  double t_end = 20.0;
  int points = 100;
  double rtol = 1e-9;
  double atol = 1e-12;
  /// The floor (Note [Perturbed truth]): each start moved by N(0, perturbation^2) per component,
  /// times perturbation_scale[c] when given (a data file's units), drawn from `seed`. 0: none.
  double perturbation = kFloorPerturbation;
  std::vector<double> perturbation_scale{};
  std::uint64_t seed = 0;
  /// Times in (0, t_end] at which the short-horizon errors are reported (chaotic systems, where
  /// errors over the whole span say little); they need not be on the grid of `points`.
  std::vector<double> horizons{};
  /// The adaptive steps a learned rollout may take before it is recorded as failed.
  long max_learned_steps = kMaxLearnedSteps;
};

// Note [Perturbed truth]: how close a perfect model could come. The true system integrated from
// starts perturbed by 1e-4 drifts from the true rollout as the system amplifies the difference
// (slowly for the oscillators, exponentially for chaotic three bodies), and the relative error
// it reaches is the floor of the relative-error metrics (Finzi et al. 2020, their repository's
// compare_rollouts: pert_eps 1e-4 times a standard normal per component, absolute, over the
// same times as the model's rollout). Their code divides |x^ - x| by |x^ + x|; their paper, and
// we, by |x^| + |x|, which keeps the error within [0, 1].

/// Rollouts from n initial states at the same times. Row i of each matrix is trajectory i.
/// Measured truth (follow_measured) may miss samples: those rows of `truth` are NaN, and every
/// metric skips them.
struct Rollouts {
  std::vector<double> t;
  std::vector<Eigen::MatrixXd> truth, pred;  // per trajectory: times x dim
  std::vector<Eigen::MatrixXd> floor;        // the perturbed truth; empty without a true system
  bool measured = false;                     // truth is measured data (follow_measured)
  std::vector<double> horizons;              // RolloutConfig::horizons
  /// Per trajectory: horizons x dim, the states at those times (floor_at empty as floor).
  std::vector<Eigen::MatrixXd> truth_at, pred_at, floor_at;
  Eigen::MatrixXd true_energy, pred_energy;  // trajectories x times
  Eigen::MatrixXd learned_h;                 // the HNN's own H along its rollout (empty if none)
  std::vector<bool> failed;                  // the learned rollout blew up (excluded from MSEs)
  std::vector<std::string> failures;         // why, with the time reached
  long nfev = 0;                             // learned-field evaluations, all trajectories
};

/// A learned field as rollouts use it: f(x), and H(x) for a model that learns one.
struct LearnedField {
  physics::VectorField field;
  std::function<Eigen::VectorXd(const Batch&)> hamiltonian{};  ///< empty: the model has none
};

/// The model's field and, for an HNN with a solenoidal part, its learned H. Refers to model.
LearnedField learned_field(const nn::DynamicsModel<double>& model);

/// Integrates the true field and the model's field from each row of x0 with the adaptive
/// Dormand-Prince 5(4) method at config.rtol. A learned rollout that blows up or whose field
/// throws is recorded as failed (with the time reached, or the error), never padded or silently
/// dropped.
Rollouts make_rollouts(const physics::System& truth, const nn::DynamicsModel<double>& model,
                       const Batch& x0, const RolloutConfig& config);
/// The same for any learned field (a model in other units, say).
Rollouts make_rollouts(const physics::System& truth, const LearnedField& learned, const Batch& x0,
                       const RolloutConfig& config);

/// Rollouts along measured paths, for data without a true system: `measured[i]` holds the states
/// at times linspace(0, config.t_end, config.points) after its first row (NaN rows where a
/// sample is missing; the first row must be there), and the learned field is integrated from
/// each first row. The horizons move to the nearest of those times (Rollouts::horizons says
/// where). Energies are NaN and there is no floor.
Rollouts follow_measured(const std::vector<Eigen::MatrixXd>& measured, const LearnedField& learned,
                         const RolloutConfig& config);

}  // namespace hnn::tasks
