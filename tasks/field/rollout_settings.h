#pragma once
// The evaluation's rollout settings of a task ("rollouts" and the span), parsed and checked in
// one place: the field tasks and the data task read theirs through it.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

/// The settings "rollouts" and the span (`span_keys`: the names that set it; giving two is an
/// error) over `defaults`, for `task`'s messages: an integer in 1..max_rollouts and a finite
/// t_end > 0; points keep the defaults' interval. The field tasks and the data task read their
/// rollouts through it.
RolloutConfig rollout_settings(const nlohmann::json& settings, RolloutConfig defaults,
                               const std::string& task, int max_rollouts,
                               const std::vector<std::string>& span_keys);

}  // namespace hnn::tasks
