#pragma once
// The error of a model along held-out trajectory stretches, each predicted from its first state:
// state MSE and SRNN's position error, with their spread over stretches.

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/train/rollout_objective.h"

namespace hnn::tasks {

/// States at a stretch's times from its first state (times x dim per stretch, batched).
using Predictor = std::function<std::vector<Batch>(const Batch& x0, const Eigen::VectorXd& t)>;

/// One path (points x dim) per stretch, predicted from its first state: one batched call when the
/// stretches share their times (the simulated tasks), else (or when the batch fails) one call per
/// stretch. A stretch whose prediction fails (a learned field that blows up) gets a NaN path and
/// counts in `failures`.
std::vector<Batch> predict_paths(const std::vector<Stretch>& stretches, const Predictor& predict,
                                 int& failures);

/// The held-out error of predicted paths against the stretches: state MSE over the points after
/// the start, and the position error (SRNN's measure: the Euclidean distance of each body's
/// position, averaged over the bodies and over every sampled time, the start included), each
/// with `_std` and `_se` over the stretches; keys start with `prefix`.
nlohmann::json stretch_errors(const std::string& prefix, const std::vector<Stretch>& stretches,
                              const std::vector<Batch>& paths, int per_body);

}  // namespace hnn::tasks
