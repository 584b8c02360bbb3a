#pragma once
// Energy errors of rollouts against the true system: the HNN paper's energy MSE and the LNN
// paper's error at the end.

#include "nn/loss.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

/// Energy MSE: mean over trajectories and times of (E(true) - E(model))^2, with a standard error
/// from 5 interleaved splits of the trajectories (the reference's "bootstrap" of 5 splits).
nn::MeanStderr energy_mse(const Rollouts& rollouts);

/// |E_pred(T) - E_true(T)| / scale at the last time T, mean over the learned rollouts that did
/// not fail, with the standard error std / sqrt(n): the LNN paper's energy metric (scale 29.4 for
/// its double pendulum). NaN when all failed.
nn::MeanStderr energy_error_at_end(const Rollouts& rollouts, double scale);

}  // namespace hnn::tasks
