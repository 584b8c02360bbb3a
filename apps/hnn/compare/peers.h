#pragma once
// hnn compare's peers: the published numbers of apps/hnn/compare/peers.json (checked entry by
// entry) and the HNN paper's Table 1 as each task gives it.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hnn::app {

/// $HNN_PEERS, the installed share/hnn/peers.json, or the source tree's
/// apps/hnn/compare/peers.json.
std::filesystem::path peers_path();

/// The peers file, checked entry by entry: one line naming the file and the entry otherwise.
nlohmann::json read_peers(const std::filesystem::path& file);

/// The HNN paper's Table 1 of those of `tasks` that are paper tasks (Task::paper(), the numbers
/// `hnn reproduce` sets beside its own), as peers that hold only at each task's own settings.
nlohmann::json table1_peers(const std::vector<std::string>& tasks);

}  // namespace hnn::app
