#pragma once
// The shared evaluator: final losses with standard errors, and rollouts of the true and learned
// fields from the same initial states for the energy metric and the charts.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "nn/loss.h"
#include "physics/system.h"

namespace hnn::tasks {

using physics::Batch;

/// How rollouts for the energy metric are made.
struct RolloutConfig {
  int trajectories = 15;
  double t_end = 20.0;
  int points = 100;
  double rtol = 1e-9;
  double atol = 1e-12;
};

/// Mean squared error of the model's field over a whole split (all N points, all D components),
/// with the reference implementation's standard error: std(N x D squared errors, n - 1
/// normalised) / sqrt(N), the convention of the paper's Table 1. Throws on an empty split.
nn::MeanStderr loss_stats(const nn::DynamicsModel<double>& model, const Batch& x,
                          const Batch& dxdt);
/// The same for any field (a model in other units, say).
nn::MeanStderr loss_stats(const physics::VectorField& field, const Batch& x, const Batch& dxdt);

/// Rollouts from n initial states at the same times. Row i of each matrix is trajectory i.
struct Rollouts {
  std::vector<double> t;
  std::vector<Eigen::MatrixXd> truth, pred;  // per trajectory: times x dim
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
/// Dormand-Prince 5(4) method at config.rtol. A learned rollout that blows up is recorded as
/// failed (with the time reached), never padded or silently dropped.
Rollouts make_rollouts(const physics::System& truth, const nn::DynamicsModel<double>& model,
                       const Batch& x0, const RolloutConfig& config);
/// The same for any learned field (a model in other units, say).
Rollouts make_rollouts(const physics::System& truth, const LearnedField& learned, const Batch& x0,
                       const RolloutConfig& config);

/// Energy MSE: mean over trajectories and times of (E(true) - E(model))^2, with a standard error
/// from 5 interleaved splits of the trajectories (the reference's "bootstrap" of 5 splits).
nn::MeanStderr energy_mse(const Rollouts& rollouts);

/// |E_pred(T) - E_true(T)| / scale at the last time T, mean over the learned rollouts that did
/// not fail, with the standard error std / sqrt(n): the LNN paper's energy metric (scale 29.4 for
/// its double pendulum). NaN when all failed.
nn::MeanStderr energy_error_at_end(const Rollouts& rollouts, double scale);

/// Mean over the learned rollouts that did not fail, their times and every state component of
/// the squared state error (the dissipative-HNN paper's state MSE); NaN when all failed.
double state_mse(const Rollouts& rollouts);

/// The relative state error e(t) = |x^ - x| / (|x^| + |x|) of the learned rollouts against the
/// true ones (Finzi et al. 2020): its geometric mean over every trajectory and time after the
/// start, and the valid prediction time, the first time e passes `threshold` (mean over the
/// trajectories; a trajectory that never passes it counts its whole span and is `censored`).
/// |x^ - x| / (|x^| + |x|) of each row (time) of a predicted path against the true one.
Eigen::VectorXd relative_state_error(const Eigen::MatrixXd& pred, const Eigen::MatrixXd& truth);

struct RelativeError {
  double geomean = NAN, valid_time = NAN;
  int censored = 0;
};
RelativeError relative_error(const Rollouts& rollouts, double threshold = 0.1);

/// Mean over trajectories of the coordinate MSE at each time (for the charts).
Eigen::VectorXd coordinate_mse_over_time(const Rollouts& rollouts);

}  // namespace hnn::tasks
