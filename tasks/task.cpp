#include "tasks/task.h"

#include <fmt/format.h>

#include <algorithm>

#include "nn/hnn.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

LoopOptions with_train_config(LoopOptions loop, const TrainConfig& config) {
  loop.steps = config.steps;
  loop.lr_schedule = config.lr_schedule;
  loop.record_every = config.record_every;
  return loop;
}

nn::AdamOptions adam_options(const TrainConfig& config) {
  return {.lr = config.learning_rate,
          .weight_decay = config.weight_decay,
          .decoupled_weight_decay = config.optimizer == OptimizerKind::kAdamW};
}

void Task::check_task_settings(const nlohmann::json& settings) const {
  HNN_TASKS_CHECK(settings.empty(), "task '{}' has no settings of its own, got {}", name(),
                  settings.dump());
}

std::unique_ptr<nn::DynamicsModel<double>> TaskRun::model_in_data_units() const {
  return nn::cast_model<double>(dynamics());
}

Eigen::VectorXd TaskRun::learned_h(const physics::Batch& x) const {
  const std::unique_ptr<nn::DynamicsModel<double>> model = model_in_data_units();
  const LearnedField learned = learned_field(*model);
  HNN_TASKS_CHECK(learned.hamiltonian,
                  "a {} model learns no scalar H (it predicts dx/dt directly): the hnn, dhnn, "
                  "lnn, hnn-mass, chnn and clnn models learn one",
                  nn::to_string(model->config().model));
  return learned.hamiltonian(x);
}

Eigen::VectorXd TaskRun::true_energy(const physics::Batch&) const { return {}; }

std::vector<std::string> TaskRun::state_names() const {
  std::vector<std::string> names;
  for (Eigen::Index c = 0; c < dynamics().config().dim; ++c)
    names.push_back(fmt::format("x_{}", c));
  return names;
}

physics::Batch TaskRun::given_states(physics::Batch x, bool project,
                                     std::vector<std::string>&) const {
  HNN_TASKS_CHECK(!project,
                  "--project moves given states onto a constrained system's constraints (the "
                  "constrained tasks in Cartesian coordinates); this run's states have none");
  return x;
}

int trajectories_to_write(const RolloutRequest& request, int available, std::string_view what) {
  if (!request.trajectories) return std::min(RolloutRequest::kDefaultTrajectories, available);
  HNN_TASKS_CHECK(*request.trajectories <= available,
                  "--trajectories {} is more than the {} {} this run can start from: give at "
                  "most {}, or your own initial states with --state or --states FILE",
                  *request.trajectories, available, what, available);
  return *request.trajectories;
}

void Task::write_comparison(const TaskRun&, const TaskRun&, const std::filesystem::path&) const {}

}  // namespace hnn::tasks
