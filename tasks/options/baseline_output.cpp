#include "tasks/options/baseline_output.h"

#include <algorithm>

#include "tasks/error.h"

namespace hnn::tasks {

std::vector<std::string> baseline_output_names() { return {"field", "accelerations"}; }

bool velocity_state(const Task& task) {
  const std::vector<nn::ModelKind> models = task.models();
  return std::find(models.begin(), models.end(), nn::ModelKind::kLnn) != models.end();
}

bool given_velocities(const nlohmann::json& settings, nn::ModelKind model, bool sampled,
                      bool velocity_state, const std::string& task) {
  if (!settings.contains(kBaselineOutputKey)) return false;
  const nlohmann::json& value = settings[kBaselineOutputKey];
  const std::vector<std::string> names = baseline_output_names();
  HNN_TASKS_CHECK(value.is_string() && std::find(names.begin(), names.end(),
                                                 value.get<std::string>()) != names.end(),
                  "{}: baseline_output must be field or accelerations, got {}", task, value.dump());
  if (value.get<std::string>() == "field") return false;
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

}  // namespace hnn::tasks
