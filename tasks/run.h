#pragma once
// One training run end to end: build the task's data, train a model, evaluate it, and write
// the run folder (metrics.json, loss_curve.csv, rollout.csv, params.bin).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "nn/dynamics.h"
#include "tasks/task.h"

namespace hnn::tasks {

struct StopSignal;

/// The widest hidden layer a run may ask for (a typo like 20000 would need gigabytes).
inline constexpr int kMaxWidth = 4096;

struct RunOptions {
  std::string task;
  std::string model = "hnn";    // hnn | baseline
  std::uint64_t seed = 0;
  std::string dtype = "double";  // float | double
  std::string preset = "paper";  // paper | lean: the task's widths (see train_config)
  int threads = 2;  // the engine's threads: fused kernels split each batch into row blocks
  std::optional<int> steps, batch_size;
  std::optional<std::vector<int>> hidden;  // overrides the preset's widths
  std::optional<double> learning_rate;
  std::string data_file;  // measured-data tasks: another file of the same format
  std::filesystem::path out;
  bool quiet = false;
  /// Training checkpoints into out/checkpoint every this many steps (default: a tenth of the
  /// steps), at the end, and when stopped.
  std::optional<long> checkpoint_every;
  /// Continue the run in `out` from its last checkpoint (see resume_options).
  bool resume = false;
  /// Polled by the training loop (e.g. set on SIGINT): checkpoint and stop after the step.
  StopSignal* stop = nullptr;
};

/// Trains and evaluates one model; writes the run folder `options.out` and returns metrics.json's
/// content. Throws on bad options or data (nothing half-written is left: each file is atomic).
nlohmann::json run_training(const RunOptions& options);

/// A finished run loaded back: its options, task, data and model (in double).
struct LoadedRun {
  RunOptions options;
  std::unique_ptr<Task> task;
  Dataset data;
  std::unique_ptr<nn::DynamicsModel<double>> model;
};

/// Reads run_dir/metrics.json and run_dir/params.bin (rebuilding the task's data from its seed).
LoadedRun load_run(const std::filesystem::path& run_dir, const std::string& data_file = "");

/// Evaluates the parameters saved in a run folder again (same task, seed and data), returning
/// the metrics without retraining.
nlohmann::json evaluate_run(const std::filesystem::path& run_dir, const std::string& data_file,
                            bool write_files);

/// Checks option values before any work: names the first bad one.
void validate(const RunOptions& options);

/// The options of the run in `run_dir`, read from its last checkpoint, with resume set: passed
/// to run_training, it continues that run and ends as the uninterrupted run would have.
RunOptions resume_options(const std::filesystem::path& run_dir);

/// Throws Error when `run_dir` holds an unfinished run (interrupted, killed or diverged), whose
/// checkpoint a fresh run would replace: the message says how to resume it instead.
void check_no_unfinished_run(const std::filesystem::path& run_dir);

}  // namespace hnn::tasks
