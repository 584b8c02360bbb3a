#pragma once
// The settings that change what a model is given, beside the task's data:
// - "baseline_output" (--baseline-output): what the baseline's MLP gives, all of dx/dt or, on a
//   state (q, v = dq/dt), the accelerations dv/dt alone with dq/dt = v given, as the LNN paper's
//   baseline does (docs/families.md, "Lagrangian NN");
// - "masses" (--masses): whether a CHNN or CLNN takes its system's masses as known or learns
//   them with its potential, as Finzi et al.'s models do (nn/constrained/masses.h).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/task.h"

namespace hnn::tasks {

/// The settings' keys and their values, the default first.
inline constexpr const char* kBaselineOutputKey = "baseline_output";
std::vector<std::string> baseline_output_names();  // "field", "accelerations"
inline constexpr const char* kMassesKey = "masses";
std::vector<std::string> masses_names();  // "known", "learned"

/// Whether the task's states are (q, dq/dt): those of a task that trains an LNN.
bool velocity_state(const Task& task);

/// Whether the run's model is given its velocities (nn::DynamicsConfig::given_velocities).
/// Throws Error naming `task` on a value other than the names, and on "accelerations" with a
/// model other than the baseline, a sampled fit (`sampled`) or a state that is not (q, dq/dt)
/// (`velocity_state`).
bool given_velocities(const nlohmann::json& settings, nn::ModelKind model, bool sampled,
                      bool velocity_state, const std::string& task);

/// Whether the run's model learns its masses (nn::ConstraintSpec::learned_masses). Throws Error
/// naming `task` on a value other than the names, and on "learned" with a model other than
/// chnn and clnn.
bool learned_masses(const nlohmann::json& settings, nn::ModelKind model, const std::string& task);

}  // namespace hnn::tasks
