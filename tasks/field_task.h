#pragma once
// The tasks that learn a field dx/dt = f(x) from states and their time derivatives (tasks 1-4b):
// each gives its dataset, its true system and where the evaluation's rollouts start; the run
// (training, evaluation, rollouts) is the same for all of them.

#include <cstdint>
#include <memory>
#include <random>
#include <string>

#include "physics/system.h"
#include "tasks/data/dataset.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/task.h"

namespace hnn::tasks {

class FieldTask : public Task {
 public:
  /// Deterministic: the same seed (and data file) give the same data, bit for bit.
  virtual Dataset build_dataset(const RunSettings& settings) const = 0;
  /// build_dataset with the task's default settings and this seed.
  Dataset build_dataset(std::uint64_t seed) const;
  /// The ground truth for rollouts and energies (a fitted H for measured data).
  virtual const physics::System& truth() const = 0;
  /// Initial states of the energy-metric rollouts.
  virtual Batch rollout_states(const Dataset& data, std::mt19937_64& rng) const = 0;
  virtual RolloutConfig rollout_config() const { return {}; }
  /// The rollouts of a run with these task settings (a task may let them change the count).
  virtual RolloutConfig rollout_config(const nlohmann::json& settings) const;
  /// Metrics of the task's own protocol from the evaluation's rollouts (a peer's), added to
  /// metrics.json; by default none.
  virtual void add_metrics(const Rollouts& rollouts, nlohmann::json& metrics) const;
  /// How many leading coordinates are angles (the models see them wrapped); by default none.
  virtual Eigen::Index angle_coordinates() const { return 0; }
  /// The models' input scales (nn::DynamicsConfig::input_scale); by default none.
  virtual std::vector<double> input_scale() const { return {}; }

  /// A FieldRun of this task; the task must outlive it.
  std::unique_ptr<TaskRun> open(const RunSettings& settings) const override;
};

/// make_task(name) as a FieldTask; throws Error when the task learns something else.
std::unique_ptr<FieldTask> make_field_task(const std::string& name);

/// Trains `model` on `data` with FieldObjective and the training loop: steps, batch size,
/// learning rate, weight decay and record interval from `config`, the rest (checkpoints, resume,
/// stop, progress) from `loop`. Minibatches are drawn from a generator seeded with `seed`.
template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, LoopOptions loop = {});

/// The dataset of a field task with its default settings and the given seed (tests, tools).
Dataset build_dataset(const std::string& task, std::uint64_t seed);

}  // namespace hnn::tasks
