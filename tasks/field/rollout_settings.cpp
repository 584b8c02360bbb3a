// The evaluation's rollouts of a field task as its settings ask: how many ("rollouts") and how
// long ("t_end" / "rollout_t_end"), read by one parser that the data task shares.

#include "tasks/field/rollout_settings.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "tasks/field/field_task.h"

namespace hnn::tasks {

using nlohmann::json;

std::vector<Eigen::MatrixXd> FieldTask::measured_paths(const RunSettings&, int,
                                                       const RolloutConfig&) const {
  throw Error(fmt::format("task '{}' has a true system, not measured paths", name()));
}

std::vector<std::string> FieldTask::evaluation_setting_names() const {
  if (scattered()) return {};  // no rollouts to set
  const std::vector<std::string> own = own_setting_names();
  std::vector<std::string> names = {"rollouts"};
  if (std::find(own.begin(), own.end(), "t_end") == own.end()) names.push_back("t_end");
  names.push_back("rollout_t_end");
  return names;
}

RolloutConfig FieldTask::rollout_config(const nlohmann::json& settings) const {
  std::vector<std::string> span = evaluation_setting_names();
  if (!span.empty()) span.erase(span.begin());  // "rollouts"
  RolloutConfig c = rollout_settings(settings, rollout_config(), name(), kMaxRollouts, span);
  c.horizons = short_horizons();
  std::erase_if(c.horizons, [&](double h) { return h > c.t_end; });
  return c;
}

RolloutConfig rollout_settings(const nlohmann::json& s, RolloutConfig defaults,
                               const std::string& task, int max_rollouts,
                               const std::vector<std::string>& span_keys) {
  RolloutConfig c = defaults;
  if (s.contains("rollouts")) {
    const json& n = s["rollouts"];
    HNN_TASKS_CHECK(n.is_number_integer() && n.get<std::int64_t>() >= 1 &&
                        n.get<std::int64_t>() <= max_rollouts,
                    "{}: rollouts must be an integer from 1 to {}, got {}", task, max_rollouts,
                    n.dump());
    c.trajectories = n.get<int>();
  }
  std::vector<std::string> given;
  for (const std::string& key : span_keys)
    if (s.contains(key)) given.push_back(key);
  HNN_TASKS_CHECK(given.size() <= 1, "{}: {} both set the rollouts' span: give one", task,
                  fmt::join(given, " and "));
  if (given.empty()) return c;
  const json& t = s[given[0]];
  HNN_TASKS_CHECK(t.is_number() && std::isfinite(t.get<double>()) && t.get<double>() > 0,
                  "{}: {} must be a finite number > 0, got {}", task, given[0], t.dump());
  const double interval = defaults.t_end / std::max(1, defaults.points - 1);
  c.t_end = t.get<double>();
  c.points = std::max(2, int(std::lround(c.t_end / interval)) + 1);
  return c;
}

}  // namespace hnn::tasks
