#pragma once
// The keys of `hnn sweep`'s spec: the options of `hnn train` that its table
// (tasks/options/train_options.h) makes sweep keys, each value checked as JSON, written as `hnn
// train` arguments and in run folder names.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "tasks/options/train_options.h"

namespace hnn::app::sweep {

/// The sweep keys, in their canonical order (of run names and table columns).
const std::vector<const tasks::TrainOption*>& key_table();
/// The sweep key named so, or nullptr.
const tasks::TrainOption* find_key(std::string_view name);
/// Why `name` (an option of `hnn train` such as threads or out) is the sweep's to set, or "".
std::string_view sweep_owned(std::string_view name);
/// The key names, in key_table's order.
std::vector<std::string> spec_keys();

/// The value in its canonical form (hidden widths as a list, a file as an absolute path, column
/// names as a list); throws std::invalid_argument saying what was expected.
nlohmann::ordered_json checked_value(const tasks::TrainOption& key,
                                     const nlohmann::ordered_json& v);
/// A canonical value as `hnn train` arguments after --KEY (--hidden 200 200: two).
std::vector<std::string> arg_values(const tasks::TrainOption& key, const nlohmann::ordered_json& v);
/// A canonical value as it reads in a run folder's name (16-16, trials-20, the file's name).
std::string name_value(const tasks::TrainOption& key, const nlohmann::ordered_json& v);

}  // namespace hnn::app::sweep
