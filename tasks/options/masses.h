#pragma once
// The setting "masses" (--masses): whether a CHNN or CLNN takes its system's masses as known or
// learns them with its potential, as Finzi et al.'s models do (nn/constrained/masses.h).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/dynamics.h"

namespace hnn::tasks {

/// The setting's key and its values: "known" (the default) and "learned".
inline constexpr const char* kMassesKey = "masses";
std::vector<std::string> masses_names();

/// Whether the run's model learns its masses (nn::ConstraintSpec::learned_masses). Throws Error
/// naming `task` on a value other than the names, and on "learned" with a model other than
/// chnn and clnn.
bool learned_masses(const nlohmann::json& settings, nn::ModelKind model, const std::string& task);

}  // namespace hnn::tasks
