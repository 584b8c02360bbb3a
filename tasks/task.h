#pragma once
// A task is one experiment of the paper: its dataset, its training configuration (the paper's
// settings as defaults), and what its evaluation needs (the true system and rollout settings).

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "physics/system.h"

namespace hnn::tasks {

using physics::Batch;

/// States and their time derivatives, split into train and test (rows are samples).
struct Dataset {
  Batch train_x, train_dxdt, test_x, test_dxdt;
};

/// How a model is trained. Every field can be overridden from the command line.
struct TrainConfig {
  int steps = 2000;
  int batch_size = 0;  // 0: full batch
  double learning_rate = 1e-3;
  double weight_decay = 0.0;
  std::vector<int> hidden = {200, 200};
  int record_every = 0;  // loss-curve interval; 0 picks about 100 points
};

/// How rollouts for the energy metric are made.
struct RolloutConfig {
  int trajectories = 15;
  double t_end = 20.0;
  int points = 100;
  double rtol = 1e-9;
  double atol = 1e-12;
};

/// One model's published numbers (reference implementation, Table 1): mean and standard error.
struct PaperValue {
  double mean = 0, se = 0;
};
struct PaperRow {
  PaperValue train_loss, test_loss, energy_mse;
};

class Task {
 public:
  virtual ~Task() = default;
  virtual std::string name() const = 0;
  /// One line for --help and reports.
  virtual std::string summary() const = 0;
  virtual TrainConfig train_config() const = 0;
  /// The `lean` preset's hidden widths: the smallest model whose test loss and energy MSE are
  /// within the noise of the paper's widths (issue 7's model-size sweep,
  /// docs/speed_accuracy.md). By default the paper's widths (a task the sweep did not cover).
  virtual std::vector<int> lean_hidden() const { return train_config().hidden; }
  virtual RolloutConfig rollout_config() const { return {}; }
  /// Deterministic: the same seed gives the same data, bit for bit.
  virtual Dataset build_dataset(std::uint64_t seed) const = 0;
  /// The ground truth for rollouts and energies (the fitted H for measured data).
  virtual const physics::System& truth() const = 0;
  /// Initial states of the energy-metric rollouts.
  virtual Batch rollout_states(const Dataset& data, std::mt19937_64& rng) const = 0;
  /// The paper's Table 1 row for "baseline" or "hnn".
  virtual PaperRow paper(const std::string& model) const = 0;
  /// Tasks on measured data read this file instead of the shipped copy.
  virtual void set_data_file(const std::string& path);
};

/// The training presets: "paper" (the paper's settings) and "lean" (lean_hidden's widths).
std::vector<std::string> preset_names();

/// The task's configuration under a preset; throws Error naming the known presets otherwise.
TrainConfig train_config(const Task& task, const std::string& preset);

/// The tasks by name: spring, pendulum, real-pendulum, two-body, three-body, pixel-pendulum.
std::unique_ptr<Task> make_task(const std::string& name);
std::vector<std::string> task_names();

}  // namespace hnn::tasks
