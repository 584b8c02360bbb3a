// The run of a field task: train a dynamics model on the task's dataset with FieldObjective,
// evaluate it against the true system, save and load it, roll it out.

#include "tasks/field_task.h"

#include "physics/integrator.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/field_model_run.h"
#include "tasks/train/field_objective.h"

namespace hnn::tasks {

namespace {

class FieldRun : public FieldModelRun {
 public:
  FieldRun(const FieldTask& task, RunSettings settings)
      : FieldModelRun(settings, task.build_dataset(settings),
                      {.angles = task.angle_coordinates(), .input_scale = task.input_scale()}),
        task_(task) {}

  nlohmann::json evaluate(const RunFolder* folder) const override {
    const RolloutConfig config = task_.rollout_config(s_.task_settings);
    FieldEvaluation e = evaluate_field_model(task_.truth(), dynamics(), data_,
                                             rollout_states(config.trajectories), config);
    task_.add_metrics(e.rollouts, e.metrics);
    if (folder) folder->write_text("rollout.csv", tasks::rollout_csv(e.rollouts));
    return e.metrics;
  }

  std::string rollout_csv(const RolloutRequest& r) const override {
    const auto integrator =
        physics::make_integrator(r.integrator, {.dt = r.dt, .rtol = r.rtol, .atol = r.rtol * 1e-3});
    return rollout_paths_csv(task_.truth(), dynamics(), nn::to_string(s_.model),
                             rollout_states(r.trajectories), *integrator,
                             physics::linspace(0.0, r.t_end.value_or(rollout_span()), r.points));
  }

  // The evaluation's states: a generator independent of the training data's draws.
  physics::Batch rollout_states(int count) const override {
    std::mt19937_64 rng(s_.seed + 1);
    physics::Batch x0 = task_.rollout_states(data_, rng);
    x0.conservativeResize(std::min<Eigen::Index>(x0.rows(), count), Eigen::NoChange);
    return x0;
  }

  double rollout_span() const override { return task_.rollout_config(s_.task_settings).t_end; }

 private:
  const FieldTask& task_;
};

}  // namespace

void FieldTask::add_metrics(const Rollouts&, nlohmann::json&) const {}

RolloutConfig FieldTask::rollout_config(const nlohmann::json&) const { return rollout_config(); }

std::unique_ptr<TaskRun> FieldTask::open(const RunSettings& settings) const {
  return std::make_unique<FieldRun>(*this, settings);
}

std::unique_ptr<FieldTask> make_field_task(const std::string& name) {
  std::unique_ptr<Task> task = make_task(name);
  HNN_TASKS_CHECK(dynamic_cast<FieldTask*>(task.get()) != nullptr,
                  "task '{}' does not learn a field from states", name);
  return std::unique_ptr<FieldTask>(static_cast<FieldTask*>(task.release()));
}

template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, LoopOptions loop) {
  loop.steps = config.steps;
  loop.record_every = config.record_every;
  FieldObjective<T> objective(model, data, config.batch_size,
                              {.lr = config.learning_rate, .weight_decay = config.weight_decay},
                              seed);
  return train(objective, loop);
}

template TrainResult train_model(nn::DynamicsModel<float>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);
template TrainResult train_model(nn::DynamicsModel<double>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);

Dataset FieldTask::build_dataset(std::uint64_t seed) const {
  return build_dataset(RunSettings{.task = name(), .seed = seed});
}

Dataset build_dataset(const std::string& task, std::uint64_t seed) {
  return make_field_task(task)->build_dataset(seed);
}

}  // namespace hnn::tasks
