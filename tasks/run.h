#pragma once
// A run end to end, the same for every task: open the task's data, train with the training
// loop (checkpoints, resume, stop), evaluate, and write the run folder (metrics.json,
// loss_curve.csv, params.bin and the task's own files). And a finished run loaded back, to
// evaluate again, roll out or measure reversibility.

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/evaluate/reversibility.h"
#include "tasks/options.h"
#include "tasks/task.h"

namespace hnn::tasks {

/// The task's defaults under the preset, with the options' overrides; throws Error naming the
/// first bad value (including an option the task does not honour).
RunSettings resolve(const Task& task, const RunOptions& options);
/// resolve() against make_task(options.task), and the options that resolve does not see.
RunSettings validate(const RunOptions& options);

/// Trains and evaluates one model; writes the run folder `options.out` and returns metrics.json's
/// content. Throws on bad options or data (nothing half-written is left: each file is atomic).
nlohmann::json run_training(const RunOptions& options);

/// The test R^2 below which a run is said to explain almost nothing of dx/dt.
inline constexpr double kLowR2 = 0.1;

/// metrics.json's "warnings": each a sentence about a run that ended no better than it started.
/// Two tests: the loss curve's last test loss (its train loss where a task has no test loss) is
/// not below its first recorded one, and the test R^2 (where a task reports one) is below
/// kLowR2. An empty curve (a run evaluated again) skips the first.
std::vector<std::string> run_warnings(const std::vector<CurvePoint>& curve,
                                      const nlohmann::json& metrics);

/// A finished run loaded back: its settings, its task and the run (data and trained model).
struct LoadedRun {
  RunSettings settings;
  std::unique_ptr<Task> task;
  std::unique_ptr<TaskRun> run;  // refers to `task`: declared after it, destroyed before it
};

/// Reads run_dir/metrics.json and run_dir/params.bin (rebuilding the task's data from its seed);
/// `data_file` replaces the run's own (measured-data tasks).
LoadedRun load_run(const std::filesystem::path& run_dir, const std::string& data_file = "");

/// The metrics of the parameters saved in a run folder, again (same task, seed and data); with
/// write_files, the evaluation's files are written again too.
nlohmann::json evaluate_run(const std::filesystem::path& run_dir, const std::string& data_file,
                            bool write_files);

/// `hnn rollout`: writes the CSV of TaskRun::rollout_csv to `out` (default
/// RUN/rollout_<integrator>.csv) and returns its path.
std::filesystem::path write_rollout(const std::filesystem::path& run_dir,
                                    const RolloutRequest& request,
                                    const std::filesystem::path& out = {});

/// Reversibility of a run's learned field from its rollout states (t_end 0: the run's rollout
/// span); writes run_dir/reversibility.json and returns it.
nlohmann::json reversibility(const std::filesystem::path& run_dir,
                             const ReversibilityOptions& options = {});

/// The options of the run in `run_dir`, read from its last checkpoint, with resume set: passed
/// to run_training, it continues that run and ends as the uninterrupted run would have.
RunOptions resume_options(const std::filesystem::path& run_dir);

/// Throws Error when `run_dir` holds an unfinished run (interrupted, killed or diverged), whose
/// checkpoint a fresh run would replace: the message says how to resume it instead.
void check_no_unfinished_run(const std::filesystem::path& run_dir);

}  // namespace hnn::tasks
