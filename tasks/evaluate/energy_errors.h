#pragma once
// Energy errors of rollouts against the true system: the HNN paper's energy MSE and the LNN
// paper's error at the end.

#include "nn/loss.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

/// Energy MSE: mean over trajectories and times of (E(true) - E(model))^2, with a standard error
/// from 5 interleaved splits of the trajectories (the reference's "bootstrap" of 5 splits).
nn::MeanStderr energy_mse(const Rollouts& rollouts);

/// The energy MSE relative to the size of the true energy: energy_mse / the mean of E(true)^2
/// over the same rollouts (those that did not fail) and times, a normalised MSE whatever H's
/// units. Its standard error is energy_mse's divided by the same mean (taken as exact). Like H
/// itself it depends on where the true H puts its zero. NaN when every rollout failed or the
/// true energy is 0 throughout.
nn::MeanStderr relative_energy_mse(const Rollouts& rollouts);

/// |E_pred(T) - E_true(T)| / scale at the last time T, mean over the learned rollouts that did
/// not fail, with the standard error std / sqrt(n): the LNN paper's energy metric (scale 29.4 for
/// its double pendulum). NaN when all failed.
nn::MeanStderr energy_error_at_end(const Rollouts& rollouts, double scale);

}  // namespace hnn::tasks
