#pragma once
// hnn compare's named studies (`--study NAME`, apps/hnn/compare/command.cpp): each a list of
// groups of tasks x models x losses, each group at its peer's protocol, so that the peer's number
// sits beside ours on the same measurement (docs/compare.md).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hnn::app {

// Tasks x models x losses, crossed; with the protocol of a peer: sweep keys of every run (`keys`)
// and of the rollout-loss runs (`rollout_keys`), the headline metric and further metrics.json keys
// for the table.
struct Group {
  std::vector<std::string> tasks, models, losses;
  nlohmann::ordered_json keys = nlohmann::ordered_json::object(),
                         rollout_keys = nlohmann::ordered_json::object();
  std::string headline;              // "": the peers file's for the task
  std::vector<std::string> metrics;  // shown on every row of the group
};

Group crossed(std::vector<std::string> tasks, std::vector<std::string> models,
              std::vector<std::string> losses);

/// The names `--study` takes, "default" first.
std::vector<std::string> study_names();

/// The groups of a study of study_names(); std::invalid_argument naming the known ones otherwise.
std::vector<Group> named_study(const std::string& name);

}  // namespace hnn::app
