#include "tasks/task.h"

#include <algorithm>
#include <functional>
#include <utility>

#include "nn/hnn.h"
#include "tasks/experiments.h"

namespace hnn::tasks {

namespace {

using Factory = std::unique_ptr<Task> (*)();

const std::vector<std::pair<std::string, Factory>>& registry() {
  static const std::vector<std::pair<std::string, Factory>> tasks = {
      {"spring", make_spring_task},
      {"pendulum", make_pendulum_task},
      {"real-pendulum", make_real_pendulum_task},
      {"two-body", make_two_body_task},
      {"three-body", make_three_body_task},
      {"pixel-pendulum", make_pixel_pendulum_task},
      {"damped-spring", make_damped_spring_task},
      {"double-pendulum", make_double_pendulum_task},
      {"real-double-pendulum", make_real_double_pendulum_task},
      {"data", make_data_task}};
  return tasks;
}

}  // namespace

void Task::check_task_settings(const nlohmann::json& settings) const {
  HNN_TASKS_CHECK(settings.empty(), "task '{}' has no settings of its own, got {}", name(),
                  settings.dump());
}

std::unique_ptr<nn::DynamicsModel<double>> TaskRun::model_in_data_units() const {
  return nn::cast_model<double>(dynamics());
}

void Task::write_comparison(const std::filesystem::path&, const std::filesystem::path&,
                            const std::filesystem::path&) const {}

std::vector<std::string> task_names() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : registry()) names.push_back(name);
  return names;
}

std::vector<std::string> paper_task_names() {
  return {"spring", "pendulum", "real-pendulum", "two-body", "three-body", "pixel-pendulum"};
}

std::unique_ptr<Task> make_task(const std::string& name) {
  for (const auto& [known, factory] : registry())
    if (known == name) return factory();
  std::string known;
  for (const std::string& n : task_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error(fmt::format("unknown task '{}' (known: {})", name, known));
}

}  // namespace hnn::tasks
