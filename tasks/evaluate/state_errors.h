#pragma once
// State errors of rollouts against the truth: the state MSE, the relative state error with its
// geometric mean, floor and valid prediction time (Finzi et al. 2020), at chosen horizons, and
// over time for the charts.

#include "nn/loss.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

/// Mean over the learned rollouts that did not fail, their times and every state component of
/// the squared state error (the dissipative-HNN paper's state MSE), with the standard error of
/// the per-trajectory means (sample std / sqrt(n)); NaN when all failed.
nn::MeanStderr state_mse(const Rollouts& rollouts);

/// |x^ - x| / (|x^| + |x|) of each row (time) of a predicted path against the true one.
Eigen::VectorXd relative_state_error(const Eigen::MatrixXd& pred, const Eigen::MatrixXd& truth);

/// The relative state error e(t) = |x^ - x| / (|x^| + |x|) of the learned rollouts against the
/// true ones (Finzi et al. 2020): its geometric mean over every trajectory and time after the
/// start, and the valid prediction time, the first time e passes `threshold` (mean over the
/// trajectories; a trajectory that never passes it counts its whole span and is `censored`).
/// Standard errors over trajectories: the valid time's is std / sqrt(n); the geometric mean's
/// is geomean * (std of the per-trajectory mean log error) / sqrt(n), the delta method's.
struct RelativeError {
  double geomean = NAN, geomean_se = NAN, valid_time = NAN, valid_time_se = NAN;
  int censored = 0, count = 0;
};
RelativeError relative_error(const Rollouts& rollouts, double threshold = 0.1);

/// relative_error of the perturbed truth against the truth over the same times: the floor of
/// Note [Perturbed truth] (its geometric mean), and the valid prediction time of a model whose
/// only error were that of its start. NaN with count 0 without a floor.
RelativeError relative_error_floor(const Rollouts& rollouts, double threshold = 0.1);

/// The errors at one of RolloutConfig::horizons, over the learned rollouts that did not fail:
/// the state MSE (mean over trajectories and components, standard error over trajectories), the
/// geometric mean of the relative state error and of the floor's (standard errors as above).
struct HorizonError {
  double t = NAN;
  nn::MeanStderr state_mse, relative_error, floor;
};
std::vector<HorizonError> horizon_errors(const Rollouts& rollouts);

/// Mean over trajectories of the coordinate MSE at each time (for the charts).
Eigen::VectorXd coordinate_mse_over_time(const Rollouts& rollouts);

}  // namespace hnn::tasks
