#pragma once
// What `hnn train` and `hnn evaluate` print for a person: a few lines made from metrics.json's
// keys. The JSON itself is in the run folder, and on stdout with --json.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hnn::app {

/// The run's task and model; its losses with standard errors and R^2 (a data run's also in the
/// standardised units of its progress line); its rollouts beside the truth's (the valid
/// prediction time beside the floor's, the energy error absolute and relative), or that a run
/// on scattered states has none; the learned H's error on the held-out points; for a sampled
/// fit, its time split and system; the time taken.
/// Each line only when the run has its keys. Ends with a newline.
std::string metrics_summary(const nlohmann::json& metrics);

/// Each of metrics["warnings"] on stderr, as "hnn: warning: ...".
void print_warnings(const nlohmann::json& metrics);

/// The names of the files in `dir` written at or after `since`, by name: "loss_curve.csv,
/// metrics.json"; "" for none.
std::string files_in(const std::filesystem::path& dir, std::filesystem::file_time_type since =
                                                           std::filesystem::file_time_type::min());

}  // namespace hnn::app
