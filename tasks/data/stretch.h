#pragma once
// Stretches of one trajectory: consecutive states at their times. The rollout loss trains on
// windows of them (tasks/train/rollout_objective.h) and the held-out evaluator predicts each from
// its first state (tasks/evaluate/held_out.h), so they live below both.

#include <vector>

#include "tasks/data/dataset.h"

namespace hnn::tasks {

/// States at their times (rows in time order), in the model's units.
struct Stretch {
  Eigen::VectorXd t;
  Batch x;
};

/// A dataset's rows as stretches of one trajectory each, split as the dataset is.
struct SplitStretches {
  std::vector<Stretch> train, test;
};

}  // namespace hnn::tasks
