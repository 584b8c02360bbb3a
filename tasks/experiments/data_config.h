#pragma once
// The `data` task's own settings (`hnn train data`'s options write them), parsed and checked.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/data/measured_dataset.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/options.h"

namespace hnn::tasks {

/// The data task's settings.
struct DataConfig {
  MeasuredDataOptions measured;
  std::string hamiltonian;  ///< empty: no known H
  bool standardize = true;
  double threshold = 0.1;
  /// With a known H: the rollouts against it from test states ("rollouts", kDefaultRollouts
  /// or as many test states as there are), over "t_end" (0: the held-out stretches' median
  /// duration). "energy_rollouts" and "energy_t_end" are their older names.
  int rollouts = kDefaultRollouts;
  double t_end = 0;
};

/// The names of the data task's settings.
const std::vector<std::string>& data_setting_names();

/// The settings of a data run; a bad value is an Error naming it.
DataConfig data_config(const nlohmann::json& settings);

/// For a file of scattered states (`source`, no time column): throws Error naming what needs
/// trajectories, the rollout loss or a setting of the rollouts or of gaps in time.
void check_scattered_settings(const nlohmann::json& settings, const RolloutLossConfig& loss,
                              const std::string& source);

}  // namespace hnn::tasks
