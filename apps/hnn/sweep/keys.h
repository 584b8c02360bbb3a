#pragma once
// The keys of `hnn sweep`'s spec: `hnn train`'s option names, each value checked, written as
// `hnn train` arguments and in run folder names, and applied to tasks::RunOptions.

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tasks/options.h"

namespace hnn::app::sweep {

/// What a key's values are.
enum class Kind {
  kTask,
  kModel,
  kSeed,
  kDtype,
  kPreset,
  kHidden,
  kPositiveInt,
  kNonNegativeInt,
  kPositiveReal,
  kFile,
  kObject,
  kColumns,
  kText,
  kSplit,
  kFraction,
  kLoss,
  kLrSchedule
};

/// One key: its name, its kind, and the data task's settings key it fills (or "").
struct KeyInfo {
  std::string_view name;
  Kind kind;
  std::string_view data_setting = "";  // the data task's settings key, as `hnn train` fills it
};

/// Every key, in the canonical order of run names and table columns.
std::span<const KeyInfo> key_table();
/// The key named so, or nullptr.
const KeyInfo* find_key(std::string_view name);
/// Why `name` (an option of `hnn train` such as threads or out) is the sweep's to set, or "".
std::string_view sweep_owned(std::string_view name);
/// The key names, in key_table's order.
std::vector<std::string> spec_keys();

/// The value in its canonical form (hidden widths as a list, a file as an absolute path, column
/// names as a list); throws std::invalid_argument saying what was expected.
nlohmann::ordered_json checked_value(const KeyInfo& key, const nlohmann::ordered_json& v);
/// A canonical value as `hnn train` arguments after --KEY (--hidden 200 200: two).
std::vector<std::string> arg_values(const KeyInfo& key, const nlohmann::ordered_json& v);
/// A canonical value as it reads in a run folder's name (16-16, trials-20, the file's name).
std::string name_value(const KeyInfo& key, const nlohmann::ordered_json& v);
/// Sets the option of `key` in `o` (not the data task's keys: their settings are the caller's).
void apply_value(const KeyInfo& key, const nlohmann::ordered_json& v, tasks::RunOptions& o);

}  // namespace hnn::app::sweep
