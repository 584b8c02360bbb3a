#include "tasks/options/masses.h"

#include <algorithm>

#include "tasks/error.h"

namespace hnn::tasks {

std::vector<std::string> masses_names() { return {"known", "learned"}; }

bool learned_masses(const nlohmann::json& settings, nn::ModelKind model, const std::string& task) {
  if (!settings.contains(kMassesKey)) return false;
  const nlohmann::json& value = settings[kMassesKey];
  const std::vector<std::string> names = masses_names();
  HNN_TASKS_CHECK(value.is_string() && std::find(names.begin(), names.end(),
                                                 value.get<std::string>()) != names.end(),
                  "{}: masses must be known or learned, got {}", task, value.dump());
  if (value.get<std::string>() == "known") return false;
  HNN_TASKS_CHECK(nn::is_constrained(model),
                  "{}: --masses learned applies to --model chnn and clnn only, not {}", task,
                  nn::to_string(model));
  return true;
}

}  // namespace hnn::tasks
