#pragma once
// The paper's Table 1: baseline and HNN trained on every task, ours beside the paper's values.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "tasks/evaluate/reversibility.h"
#include "tasks/options.h"

namespace hnn::tasks {

struct ReproduceOptions {
  std::vector<std::string> tasks;  // empty: every task
  int seeds = 1;                   // seeds 0 .. seeds-1, averaged
  std::optional<Dtype> dtype;      // unset: each task's (Task::default_dtype)
  Preset preset = Preset::kPaper;  // each task's widths, see Task::lean_hidden
  int jobs = 2;                    // runs trained at once (sharing the cores)
  std::optional<int> steps;        // override every task's step count (quick looks)
  std::filesystem::path out = "results";
  bool quiet = false;
  bool reversibility = true;  // also write reversibility.md/.json over every run
};

/// Runs everything into out/<task>/<model>[/seed-<s>], then writes out/table1.json and
/// out/table1.md. Returns table1.json's content.
nlohmann::json reproduce(const ReproduceOptions& options);

/// Every run under `results` (results/<task>/<model>[/seed-0]): reversibility.json in each, and
/// results/reversibility.json and reversibility.md side by side for the models.
nlohmann::json reversibility_report(const std::filesystem::path& results,
                                    const ReversibilityOptions& options = {});

}  // namespace hnn::tasks
