#pragma once
// A task is one experiment: its defaults (the paper's settings) and how a run of it goes (its
// Table 1 row is in data/peers.json, read by tasks/studies/published.h). Every task, the pixel
// pendulum included, is registered by name (make_task) and offers the same entry points through
// TaskRun: build the data, train, evaluate, save and load, roll out. The flow of a run
// (tasks/run.h): task -> data -> train -> evaluate -> report.

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nn/dynamics.h"
#include "nn/optim.h"
#include "physics/types.h"
#include "tasks/error.h"
#include "tasks/options.h"
#include "tasks/train/loop.h"

namespace hnn::tasks {

/// `hnn rollout`: the learned model's paths (and the truth's) from test states or given ones.
struct RolloutRequest {
  std::string integrator = "dopri5";
  double dt = 1e-2, rtol = 1e-9;
  std::optional<double> t_end{};  // default: the evaluation's rollout span
  int points = 200;
  /// How many test states to start from; unset: kDefaultTrajectories, or fewer when the run
  /// has fewer. More than the run has is an Error (trajectories_to_write).
  std::optional<int> trajectories{};
  /// Given initial states, one per row, in the run's state order (TaskRun::state_names) and the
  /// data's units; empty: the run's test states.
  physics::Batch initial_states{};

  static constexpr int kDefaultTrajectories = 5;
};

/// What `hnn rollout` wrote: the CSV (tasks/report/rollout_csv.h), how many trajectories it
/// holds, and notes for the terminal (a truth that is unavailable, say).
struct RolloutOutput {
  std::string csv;
  int trajectories = 0;
  std::vector<std::string> notes{};
};

/// How many of the run's `available` test states (`what`: "held-out stretches", say) a
/// request rolls out: its trajectories, or by default up to kDefaultTrajectories. Throws Error
/// when it asks for more than there are, naming both counts and --states.
int trajectories_to_write(const RolloutRequest& request, int available, std::string_view what);

/// `loop` with the steps, learning-rate schedule and loss-curve interval of `config`: every run
/// trains with its own settings' (TaskRun::train), whoever made the loop.
LoopOptions with_train_config(LoopOptions loop, const TrainConfig& config);
/// Adam's options from the run's: learning rate, weight decay and where it acts.
nn::AdamOptions adam_options(const TrainConfig& config);

/// One run of a task: its data (built when the run is opened) and its model.
class TaskRun {
 public:
  virtual ~TaskRun() = default;
  /// Trains a fresh model, initialised from the run's seed, with the training loop: its steps,
  /// schedule and loss-curve interval from the run's settings (with_train_config).
  virtual TrainResult train(const LoopOptions& loop) = 0;
  /// The trained model's parameters, in the run's dtype (nn's parameter file).
  virtual void save(const std::filesystem::path& params) const = 0;
  virtual void load(const std::filesystem::path& params) = 0;
  /// The metrics of metrics.json; with a folder, also the task's evaluation files.
  virtual nlohmann::json evaluate(const RunFolder* folder) const = 0;
  /// `hnn rollout`: the model's paths (and the truth's where the run knows it) over the
  /// request's span, from its initial states or the run's test states.
  virtual RolloutOutput rollout(const RolloutRequest& request) const = 0;
  /// The names of the state's columns, in order: what `hnn rollout --states FILE` names and
  /// rollout CSVs use. By default x_0..x_{d-1}.
  virtual std::vector<std::string> state_names() const;
  /// States given to `hnn rollout` (rows, in state_names()' order), as the truth starts from
  /// them. A constrained system's run refuses one off its constraints, naming it and the
  /// constraint, or with `project` moves them onto the constraints and says how far in `notes`.
  /// By default they are used as given, and `project` is refused: there is nothing to move
  /// them onto.
  virtual physics::Batch given_states(physics::Batch x, bool project,
                                      std::vector<std::string>& notes) const;

  /// The learned field (in double) and the states its rollouts start from: the phase space, or
  /// the latent space of a task that learns one. For reversibility and the like.
  virtual const nn::DynamicsModel<double>& dynamics() const = 0;
  virtual physics::Batch rollout_states(int count) const = 0;
  /// The span of the evaluation's rollouts, in the dynamics' time unit.
  virtual double rollout_span() const = 0;
  /// "state" (phase space) or "latent".
  virtual std::string space() const { return "state"; }
  /// The trained model as a user sees it, for `hnn export`: in the data's own units (a task
  /// that trains in other units folds them into the weights). By default dynamics() in double.
  virtual std::unique_ptr<nn::DynamicsModel<double>> model_in_data_units() const;
  /// The learned H of states (rows, in the data's units: those of state_names()), for `hnn
  /// hamiltonian`; by default model_in_data_units()'s. Throws Error for a model that learns no
  /// scalar (a baseline).
  virtual Eigen::VectorXd learned_h(const physics::Batch& x) const;
  /// The true energy of the same states where the run knows its H (a field task's system, a
  /// data run's --hamiltonian); empty otherwise (the default).
  virtual Eigen::VectorXd true_energy(const physics::Batch& x) const;
};

class Task {
 public:
  virtual ~Task() = default;
  virtual std::string name() const = 0;
  /// One line for --help and reports.
  virtual std::string summary() const = 0;
  /// The paper's training settings.
  virtual TrainConfig train_config() const = 0;
  /// The `lean` preset's hidden widths: the smallest model whose test loss and energy MSE are
  /// within the noise of the paper's widths (the model-size sweep, docs/speed_accuracy.md). By
  /// default the paper's widths (a task the sweep did not cover).
  virtual std::vector<int> lean_hidden() const { return train_config().hidden; }
  /// A paragraph under Table 1 when this task's metrics mean something particular.
  virtual std::string table_note() const { return ""; }
  /// A figure comparing a trained baseline run and a trained HNN run of this task into `out`,
  /// for `hnn reproduce`, when has_comparison(); by default none.
  virtual bool has_comparison() const { return false; }
  virtual void write_comparison(const TaskRun& baseline, const TaskRun& hnn,
                                const std::filesystem::path& out) const;
  /// The model kinds a run of this task can train: by default hnn, baseline and dhnn.
  virtual std::vector<nn::ModelKind> models() const {
    return {nn::ModelKind::kHnn, nn::ModelKind::kBaseline, nn::ModelKind::kDhnn};
  }
  /// Why a model kind outside models() does not fit this task, appended to the refusal ("" by
  /// default: the list of its models says enough).
  virtual std::string refusal_reason(nn::ModelKind) const { return ""; }
  /// The loss a run trains with when its settings name none (tasks/train/rollout_objective.h);
  /// by default dx/dt targets.
  virtual RolloutLossConfig default_loss() const { return {}; }
  /// The scalar type a run trains in when --dtype names none; by default double.
  virtual Dtype default_dtype() const { return Dtype::kDouble; }
  /// Whether --data FILE applies (tasks on measured data).
  virtual bool reads_data_file() const { return false; }
  /// Checks the task's own settings (RunSettings::task_settings); throws Error naming an unknown
  /// key or a bad value. By default a task has none.
  virtual void check_task_settings(const nlohmann::json& settings) const;
  /// Builds the run's data (deterministic: the same settings give the same data, bit for bit).
  virtual std::unique_ptr<TaskRun> open(const RunSettings& settings) const = 0;
};

}  // namespace hnn::tasks
