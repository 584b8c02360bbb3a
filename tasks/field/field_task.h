#pragma once
// The tasks that learn a field dx/dt = f(x) from states and their time derivatives (tasks 1-4b):
// each gives its dataset, its true system and where the evaluation's rollouts start; the run
// (training, evaluation, rollouts) is the same for all of them.

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include "physics/system.h"
#include "tasks/data/dataset.h"
#include "tasks/data/stretch.h"
#include "tasks/data/trajectories.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/task.h"

namespace hnn::tasks {

/// Rows in blocks of `points` consecutive states, sampled at linspace(0, t_end, points).
std::vector<Stretch> regular_stretches(const Batch& x, int points, double t_end);

/// Spring and pendulum: the task settings "t_end" (each trajectory's span) and "sample_dt" (the
/// sampling interval, which must divide t_end) over the paper's sampling; throws Error naming
/// `task` on a bad value. Without them, `paper` as it is.
OscillatorSettings oscillator_settings(const nlohmann::json& settings, OscillatorSettings paper,
                                       const std::string& task);

class FieldTask : public Task {
 public:
  /// Deterministic: the same seed (and data file) give the same data, bit for bit.
  virtual Dataset build_dataset(const RunSettings& settings) const = 0;
  /// build_dataset with the task's default settings and this seed.
  Dataset build_dataset(std::uint64_t seed) const;
  /// The ground truth for rollouts and energies (a fitted H for measured data). A task without
  /// one (has_truth() false) throws Error.
  virtual const physics::System& truth() const = 0;
  /// The truth of a run with these settings when they change it (Hénon–Heiles' alpha, say);
  /// by default none, and the run uses truth().
  virtual std::unique_ptr<physics::System> truth_for(const RunSettings&) const { return nullptr; }
  /// Whether truth() exists. A task on measured data without a true system says no and gives
  /// measured_paths instead: its rollouts follow held-out measurements.
  virtual bool has_truth() const { return true; }
  /// Up to `count` measured paths on the times of `config` with their missing samples NaN (the
  /// truth of follow_measured), for a task without a truth; by default none.
  virtual std::vector<Eigen::MatrixXd> measured_paths(const RunSettings& settings, int count,
                                                      const RolloutConfig& config) const;
  /// Whether the data are states scattered over a domain with exact derivatives, not
  /// trajectories (the sampled-HNN paper's protocols): the evaluation judges the held-out points
  /// alone (evaluate_field_points) and has no rollouts nor their settings. By default no.
  virtual bool scattered() const { return false; }
  /// Initial states of the evaluation's rollouts: `count` of them, or as many distinct ones as
  /// the task's data have when that is fewer.
  virtual Batch rollout_states(const Dataset& data, int count, std::mt19937_64& rng) const = 0;
  /// The rollouts with the task's defaults: kDefaultRollouts of them unless the data have fewer
  /// distinct initial states.
  virtual RolloutConfig rollout_config() const { return {}; }
  /// The rollouts of a run with its task settings applied: "rollouts" (1..kMaxRollouts) and the
  /// span "rollout_t_end", or "t_end" where the task has no data setting of that name (spring
  /// and pendulum do: their trajectories' span). A span changes the number of points to keep
  /// the default's sampling interval; horizons beyond it are dropped. Throws Error naming the
  /// task on a bad value.
  RolloutConfig rollout_config(const nlohmann::json& settings) const;
  /// Times at which the short-horizon errors are reported (RolloutConfig::horizons), for tasks
  /// whose long-horizon errors chaos dominates; by default none.
  virtual std::vector<double> short_horizons() const { return {}; }
  /// Metrics of the task's own protocol from the evaluation's rollouts (a peer's), added to
  /// metrics.json; by default none.
  virtual void add_metrics(const Rollouts& rollouts, nlohmann::json& metrics) const;
  /// How many leading coordinates are angles (the models see each as (cos, sin)); by default none.
  virtual Eigen::Index angle_coordinates() const { return 0; }
  /// The constrained system a CHNN or CLNN is built on (points, masses, constraints); empty
  /// where the task has none, and those models are not among its models().
  virtual nn::ConstraintSpec constraints() const { return {}; }
  /// Why row `row` of states given to `hnn rollout` cannot start the truth (a constrained
  /// system's state off its constraints), in words; empty when it can. By default every state can.
  virtual std::string state_problem(const Batch& x, Eigen::Index row) const;
  /// Given states moved onto the truth's constraints (`hnn rollout --project`), and the largest
  /// move. By default an Error: the task's states have no constraints.
  virtual std::pair<Batch, double> project_states(const Batch& x) const;
  /// The models' input scales (nn::DynamicsConfig::input_scale); by default none.
  virtual std::vector<double> input_scale() const { return {}; }

  /// The dataset's rows as stretches along their trajectories (consecutive states with their
  /// times), split as `data` is: what the rollout loss trains on and its held-out error is
  /// measured on. By default none: rows that are not trajectories (a grid of states, say).
  virtual std::optional<SplitStretches> stretches(const RunSettings& settings,
                                                  const Dataset& data) const;
  /// Position coordinates per body, for the position error (2 for the planar n-body tasks).
  virtual int coordinates_per_body() const { return 1; }
  /// The task's own settings besides the rollout loss's (loss, horizon, integrator, dt) and the
  /// evaluation's (evaluation_setting_names).
  virtual std::vector<std::string> own_setting_names() const { return {}; }
  /// The evaluation's rollouts: "rollouts", "t_end" unless own_setting_names() has it, and
  /// "rollout_t_end"; none for scattered() data.
  std::vector<std::string> evaluation_setting_names() const;
  /// Checks the rollout-loss keys, the rollouts' and own_setting_names(); a task with settings
  /// of its own checks their values in build_dataset (before a run folder exists).
  void check_task_settings(const nlohmann::json& settings) const override;

  /// A FieldRun of this task; the task must outlive it.
  std::unique_ptr<TaskRun> open(const RunSettings& settings) const override;
};

}  // namespace hnn::tasks
