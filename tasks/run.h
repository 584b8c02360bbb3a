#pragma once
// A run end to end, the same for every task: open the task's data, train with the training
// loop (checkpoints, resume, stop), evaluate, and write the run folder (metrics.json,
// loss_curve.csv, params.bin and the task's own files). And a finished run loaded back, to
// evaluate again, roll out or measure reversibility.

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "tasks/evaluate/reversibility.h"
#include "tasks/evaluate/run_warnings.h"
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
/// A fresh run refuses a folder that is not empty (check_new_run_folder); with options.force
/// the run it holds is removed, file by file, once the new run's data are read. The data file
/// is recorded by its absolute path and SHA-256 (RunSettings::data_sha256).
nlohmann::json run_training(const RunOptions& options);

/// `hnn train`'s folder without --out: runs/TASK/MODEL, or runs/TASK/STEM/MODEL for a data file
/// STEM.EXT, so that the runs of two files do not share a folder.
std::filesystem::path default_run_folder(const RunOptions& options);

/// A finished run loaded back: its settings, its task and the run (data and trained model).
struct LoadedRun {
  RunSettings settings;
  std::unique_ptr<Task> task;
  std::unique_ptr<TaskRun> run;  // refers to `task`: declared after it, destroyed before it
};

/// Which data a run is loaded with (measured-data tasks).
enum class DataFileUse {
  /// The run's own: at the recorded absolute path, or at `data_file` when it has moved; a file
  /// whose SHA-256 is not the recorded one is refused (runs from before the checksum: any).
  kRunsOwn,
  /// `data_file`, another file of the same format (`hnn evaluate --data`).
  kOther,
};

/// Reads run_dir/metrics.json and run_dir/params.bin (rebuilding the task's data from its seed
/// or its data file, as `use` says). Throws Error with one line when the data file is missing
/// or not the run's.
LoadedRun load_run(const std::filesystem::path& run_dir, const std::string& data_file = "",
                   DataFileUse use = DataFileUse::kRunsOwn);

/// The metrics of the parameters saved in a run folder, again (same task and seed; the run's own
/// data, or `data_file`, another file); with write_files, the evaluation's files are written
/// again too.
nlohmann::json evaluate_run(const std::filesystem::path& run_dir, const std::string& data_file,
                            bool write_files);

/// `hnn rollout`'s input: the request; its initial states as the user gave them, `--state`
/// values or a `--states` file (neither: the run's test states); a data file replacing the
/// run's (load_run); the CSV's path (default RUN/rollout_<integrator>.csv).
struct RolloutCommand {
  RolloutRequest request{};
  std::vector<std::string> states{};
  std::string states_file{};
  bool project = false;  ///< move the given states onto a constrained system's constraints
  std::string data_file{};
  std::filesystem::path out{};
};

/// What write_rollout wrote: the CSV's path, its number of trajectories, notes for the terminal.
struct RolloutWritten {
  std::filesystem::path path;
  int trajectories = 0;
  std::vector<std::string> notes{};
};

/// `hnn rollout`: reads the initial states against the run's state columns
/// (tasks/data/initial_states.h) and writes the CSV of TaskRun::rollout.
RolloutWritten write_rollout(const std::filesystem::path& run_dir, const RolloutCommand& command);

/// Reversibility of a run's learned field from its rollout states (t_end 0: the run's rollout
/// span); writes run_dir/reversibility.json and returns it. `data_file`: the run's own data file
/// at a new place (load_run's kRunsOwn: its SHA-256 must be the run's).
nlohmann::json reversibility(const std::filesystem::path& run_dir,
                             const ReversibilityOptions& options = {},
                             const std::string& data_file = "");

/// The options of the run in `run_dir`, read from its last checkpoint, with resume set: passed
/// to run_training, it continues that run and ends as the uninterrupted run would have. With
/// `steps` more than a finished run's, it goes on to that many (recorded in continued_from),
/// and ends as a run trained for `steps` from the start would have; refused for an unfinished
/// run, fewer steps, or a cosine schedule (which would start again from the decayed rate).
RunOptions resume_options(const std::filesystem::path& run_dir,
                          std::optional<int> steps = std::nullopt);

/// Throws Error when `run_dir` holds an unfinished run (interrupted, killed or diverged), whose
/// checkpoint a fresh run would replace: the message says how to resume it instead.
void check_no_unfinished_run(const std::filesystem::path& run_dir);

/// Throws Error unless `out` may take a fresh run: missing, empty, or (with force) holding a
/// run, finished or not. A folder holding other files is refused even with force.
void check_new_run_folder(const std::filesystem::path& out, bool force);

}  // namespace hnn::tasks
