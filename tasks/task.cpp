#include "tasks/task.h"

#include <algorithm>

#include "nn/hnn.h"

namespace hnn::tasks {

LoopOptions with_train_config(LoopOptions loop, const TrainConfig& config) {
  loop.steps = config.steps;
  loop.lr_schedule = config.lr_schedule;
  loop.record_every = config.record_every;
  return loop;
}

void Task::check_task_settings(const nlohmann::json& settings) const {
  HNN_TASKS_CHECK(settings.empty(), "task '{}' has no settings of its own, got {}", name(),
                  settings.dump());
}

std::unique_ptr<nn::DynamicsModel<double>> TaskRun::model_in_data_units() const {
  return nn::cast_model<double>(dynamics());
}

void Task::write_comparison(const TaskRun&, const TaskRun&, const std::filesystem::path&) const {}

}  // namespace hnn::tasks
