#pragma once
// reversibility.md: the return distances and flow-map determinants of every run of a results
// folder, one row per task and model, and why any cell failed.

#include <nlohmann/json.hpp>
#include <string>

namespace hnn::tasks {

/// From reversibility.json's rows (each with task, model, integrators and volume).
std::string reversibility_markdown(const nlohmann::json& rows);

}  // namespace hnn::tasks
