#include "tasks/options/model_settings.h"

#include <fmt/ranges.h>

#include <algorithm>

#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// The value of the choice setting `key` in `settings`, names[0] when it is absent; throws Error
// naming `task` on anything but one of the names.
std::string choice(const nlohmann::json& settings, const char* key,
                   const std::vector<std::string>& names, const std::string& task) {
  if (!settings.contains(key)) return names.front();
  const nlohmann::json& value = settings[key];
  HNN_TASKS_CHECK(value.is_string() && std::find(names.begin(), names.end(),
                                                 value.get<std::string>()) != names.end(),
                  "{}: {} must be {}, got {}", task, key, fmt::join(names, " or "), value.dump());
  return value.get<std::string>();
}

}  // namespace

std::vector<std::string> baseline_output_names() { return {"field", "accelerations"}; }
std::vector<std::string> masses_names() { return {"known", "learned"}; }

bool velocity_state(const Task& task) {
  const std::vector<nn::ModelKind> models = task.models();
  return std::find(models.begin(), models.end(), nn::ModelKind::kLnn) != models.end();
}

bool given_velocities(const nlohmann::json& settings, nn::ModelKind model, bool sampled,
                      bool velocity_state, const std::string& task) {
  if (choice(settings, kBaselineOutputKey, baseline_output_names(), task) == "field") return false;
  HNN_TASKS_CHECK(model == nn::ModelKind::kBaseline,
                  "{}: --baseline-output accelerations applies to --model baseline only, not {}",
                  task, nn::to_string(model));
  HNN_TASKS_CHECK(velocity_state,
                  "{}: --baseline-output accelerations needs a state (q, dq/dt); this task's "
                  "second half is not dq/dt",
                  task);
  HNN_TASKS_CHECK(!sampled, "{}: --baseline-output accelerations does not apply to a sampled fit",
                  task);
  return true;
}

bool learned_masses(const nlohmann::json& settings, nn::ModelKind model, const std::string& task) {
  if (choice(settings, kMassesKey, masses_names(), task) == "known") return false;
  HNN_TASKS_CHECK(nn::is_constrained(model),
                  "{}: --masses learned applies to --model chnn and clnn only, not {}", task,
                  nn::to_string(model));
  return true;
}

}  // namespace hnn::tasks
