// The data task's settings (data_config.h).

#include "tasks/experiments/data_config.h"

#include <fmt/format.h>

#include <optional>

#include "nn/enum_names.h"
#include "tasks/error.h"
#include "tasks/field/rollout_settings.h"
#include "tasks/train/fit_method.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// A column list: an array of names or indices, or one name.
std::vector<std::string> columns(const json& j) {
  const json list = j.is_array() ? j : json::array({j});
  std::vector<std::string> out;
  for (const json& c : list) out.push_back(c.is_string() ? c.get<std::string>() : c.dump());
  return out;
}

SplitBy parse_split(const std::string& name) {
  if (const std::optional<SplitBy> split = nn::find_name(kSplitByNames, name)) return *split;
  throw Error(
      fmt::format("data: split '{}' is not one of {}", name, nn::join_names(kSplitByNames)));
}

}  // namespace

const std::vector<std::string>& data_setting_names() {
  static const std::vector<std::string> names = {"coords",
                                                 "momenta",
                                                 "velocities",
                                                 "derivatives",
                                                 "time",
                                                 "trajectory",
                                                 "split",
                                                 "test_fraction",
                                                 "gap_factor",
                                                 "hamiltonian",
                                                 "standardize",
                                                 "threshold",
                                                 "rollouts",
                                                 "t_end",
                                                 "loss",
                                                 "horizon",
                                                 "integrator",
                                                 "dt",
                                                 "norm",
                                                 "minibatches",
                                                 "energy_rollouts",
                                                 "energy_t_end",
                                                 "baseline_output",
                                                 "masses"};
  static const std::vector<std::string> with_fit = [] {
    std::vector<std::string> all = names;
    all.insert(all.end(), fit_setting_names().begin(), fit_setting_names().end());
    return all;
  }();
  return with_fit;
}

DataConfig data_config(const json& s) {
  DataConfig c;
  ColumnChoice& col = c.measured.columns;
  try {
    if (s.contains("coords")) col.coords = columns(s["coords"]);
    if (s.contains("momenta")) col.momenta = columns(s["momenta"]);
    if (s.contains("velocities")) col.velocities = columns(s["velocities"]);
    if (s.contains("derivatives")) col.derivatives = columns(s["derivatives"]);
    if (s.contains("time")) col.time = columns(s["time"]).at(0);
    if (s.contains("trajectory")) col.trajectory = columns(s["trajectory"]).at(0);
    col.gap_factor = s.value("gap_factor", col.gap_factor);
    c.measured.split.by = parse_split(s.value("split", std::string("auto")));
    c.measured.split.test_fraction = s.value("test_fraction", c.measured.split.test_fraction);
    c.hamiltonian = s.value("hamiltonian", std::string());
    c.standardize = s.value("standardize", true);
    c.threshold = s.value("threshold", c.threshold);
  } catch (const json::exception& e) {
    throw Error(fmt::format("data: bad task settings {}: {}", s.dump(), e.what()));
  }
  HNN_TASKS_CHECK(c.threshold > 0 && c.threshold < 1,
                  "data: threshold {} is not between 0 and 1 (a relative state error)",
                  c.threshold);
  // The rollouts' settings as every field task reads them, under either name.
  json rollouts = s;
  if (s.contains("energy_rollouts")) {
    HNN_TASKS_CHECK(!s.contains("rollouts"),
                    "data: rollouts and energy_rollouts (its older name) are both given: give one");
    rollouts["rollouts"] = s["energy_rollouts"];
  }
  const RolloutConfig r = rollout_settings(rollouts, {.t_end = 1.0, .points = 2}, "data",
                                           kMaxRollouts, {"t_end", "energy_t_end"});
  c.rollouts = r.trajectories;
  if (s.contains("t_end") || s.contains("energy_t_end")) c.t_end = r.t_end;
  return c;
}

void check_scattered_settings(const json& settings, const RolloutLossConfig& loss,
                              const std::string& source) {
  HNN_TASKS_CHECK(!loss.rollout,
                  "{}: the rollout loss needs trajectories, and the file holds scattered states "
                  "(no time column): use --loss derivative",
                  source);
  for (const char* key :
       {"rollouts", "t_end", "energy_rollouts", "energy_t_end", "threshold", "gap_factor"}) {
    HNN_TASKS_CHECK(!settings.contains(key),
                    "{}: the setting {} needs trajectories, and the file holds scattered states "
                    "(no time column): leave it out",
                    source, key);
  }
}

}  // namespace hnn::tasks
