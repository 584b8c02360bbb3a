#pragma once
// The setting "baseline_output" (--baseline-output): what the baseline's MLP gives, all of dx/dt
// or, on a state (q, v = dq/dt), the accelerations dv/dt alone with dq/dt = v given, as the LNN
// paper's baseline does (docs/families.md, "Lagrangian NN").

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/task.h"

namespace hnn::tasks {

/// The setting's key and its values: "field" (the default) and "accelerations".
inline constexpr const char* kBaselineOutputKey = "baseline_output";
std::vector<std::string> baseline_output_names();

/// Whether the task's states are (q, dq/dt): those of a task that trains an LNN.
bool velocity_state(const Task& task);

/// Whether the run's model is given its velocities (nn::DynamicsConfig::given_velocities).
/// Throws Error naming `task` on a value other than the names, and on "accelerations" with a
/// model other than the baseline, a sampled fit (`sampled`) or a state that is not (q, dq/dt)
/// (`velocity_state`).
bool given_velocities(const nlohmann::json& settings, nn::ModelKind model, bool sampled,
                      bool velocity_state, const std::string& task);

}  // namespace hnn::tasks
