#pragma once
// `hnn sweep`'s spec: a JSON or YAML file whose keys are `hnn train`'s option names, each with a
// list of values to cross, read, checked and expanded to runs here, before anything runs. Every
// mistake is one line naming the key (docs/sweeps.md has the format).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hnn::app::sweep {

/// One run of a sweep: an ordinary `hnn train` run folder, OUT/runs/<name>.
struct SweepRun {
  std::string name;               // task/model/key=value,... (the values the spec gives)
  nlohmann::ordered_json values;  // spec key -> this run's value
  std::vector<std::string> args;  // `hnn train` arguments, without --threads, --quiet, --out
  nlohmann::json settings;        // the resolved settings, as metrics.json holds them
};

/// A spec expanded: its runs (the grids' union, each distinct run once) and its charts.
struct SweepPlan {
  std::vector<SweepRun> runs;
  std::vector<std::string> keys;  // every spec key any run sets, in the canonical order
  nlohmann::json charts = nlohmann::json::array();
};

/// The spec file's content: JSON, or YAML for a .yaml/.yml file. Throws std::invalid_argument
/// "sweep spec FILE: ..." when it cannot be read or parsed.
nlohmann::ordered_json read_spec(const std::filesystem::path& file);

/// Checks every key and value of `spec`, expands its grids and checks each run as `hnn train`
/// would (task, model, settings), with run folders under `out`/runs. Throws
/// std::invalid_argument "`where`: key 'x': ..." (or "run 'name': ...") at the first problem.
SweepPlan expand(const nlohmann::ordered_json& spec, const std::string& where,
                 const std::filesystem::path& out);

}  // namespace hnn::app::sweep
