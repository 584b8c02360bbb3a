#pragma once
// `hnn evaluate RUN --against OTHER`: two runs of one task and the same data side by side, from
// their metrics.json's keys: the losses, R^2, the valid prediction time and the energy error,
// with the ratio OTHER / RUN.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hnn::app {

/// Throws std::runtime_error, one line naming both folders and what differs, unless the runs
/// of `run` and `other` (their metrics.json) are of the same task and data: the task, the seed
/// (which draws a task's data and rollout states), the task's settings and the data file's
/// SHA-256.
void check_comparable(const std::filesystem::path& run, const std::filesystem::path& other);

/// The table of the two runs' metrics, each row only when both have its key. Ends with a
/// newline.
std::string comparison_table(const nlohmann::json& run, const std::string& run_name,
                             const nlohmann::json& other, const std::string& other_name);

}  // namespace hnn::app
