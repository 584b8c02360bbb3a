#pragma once
// The paper's Table 1 as markdown: our rows (mean ± standard error over seeds) beside the
// paper's, baseline / HNN, with the training times.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hnn::tasks {

/// table1.md from table1.json's rows (one per task and model, with paper_* values); `notes` are
/// paragraphs appended under the table (what a task's metrics mean when they differ).
std::string table1_markdown(const nlohmann::json& rows, double wall_seconds,
                            const std::vector<std::string>& notes = {});

}  // namespace hnn::tasks
