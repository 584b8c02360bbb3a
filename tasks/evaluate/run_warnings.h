#pragma once
// The warnings of a run that ended no better than it started, or whose integrator cannot follow
// the true motion: on stderr and in metrics.json's "warnings", after training (tasks/run.cpp)
// and after an evaluation.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/report/run_folder.h"

namespace hnn::tasks {

/// The test R^2 below which a run is said to explain almost nothing of dx/dt.
inline constexpr double kLowR2 = 0.1;

/// A training loss this many times below the true system's own (truth_rollout_loss) says the
/// integrator cannot follow the true motion at the run's step.
inline constexpr double kTruthLossRatio = 10;

/// metrics.json's "warnings": each a sentence about a run that ended no better than it started,
/// or learned something else than the true motion. Three tests: the loss curve's last test loss
/// (its train loss where a task has no test loss) is not below its first recorded one; the true
/// system's rollout loss through the training's integrator is over kTruthLossRatio times the
/// curve's last train loss; and the test R^2 (where a task reports one) is below kLowR2. An
/// empty curve (a run evaluated again) skips the first two.
std::vector<std::string> run_warnings(const std::vector<CurvePoint>& curve,
                                      const nlohmann::json& metrics);

}  // namespace hnn::tasks
