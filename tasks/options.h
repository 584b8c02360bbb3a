#pragma once
// A run's options, typed and checked in one place: what a user asks for (RunOptions: a task, a
// model and overrides of the task's defaults) and what a run is once resolved against its task
// (RunSettings: every value set, as metrics.json and checkpoints record it).

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/train/fit_method.h"
#include "tasks/train/loop.h"
#include "tasks/train/rollout_objective.h"

namespace hnn::tasks {

/// The widest hidden layer a run may ask for (a typo like 50000 would need gigabytes): a sampled
/// fit's (the peer protocols' 5000 wide layers, tasks/train/fit_method.h); Adam's steps take at
/// most kMaxAdamWidth.
inline constexpr int kMaxWidth = 8192;
inline constexpr int kMaxAdamWidth = 4096;

/// Where Adam's weight decay acts: added to the gradient as an L2 term (torch.optim.Adam), or
/// decoupled from the moments (torch.optim.AdamW; nn::AdamOptions::decoupled_weight_decay).
enum class OptimizerKind { kAdam, kAdamW };

/// How a model is trained. Every field can be overridden from the command line.
struct TrainConfig {
  int steps = 2000;
  int batch_size = 0;  // 0: full batch
  double learning_rate = 1e-3;
  double weight_decay = 0.0;
  LrSchedule lr_schedule = LrSchedule::kConstant;
  OptimizerKind optimizer = OptimizerKind::kAdam;  // where weight_decay acts
  std::vector<int> hidden = {200, 200};
  int record_every = 0;  // loss-curve interval; 0 picks about 100 points
};

enum class Dtype { kFloat, kDouble };
/// The training presets: the paper's widths, or each task's lean widths (Task::lean_hidden).
enum class Preset { kPaper, kLean };

std::string_view to_string(Dtype dtype);
std::string_view to_string(Preset preset);
std::string_view to_string(OptimizerKind optimizer);
/// Inverses of to_string; throw Error naming the valid values.
Dtype parse_dtype(std::string_view name);
Preset parse_preset(std::string_view name);
OptimizerKind parse_optimizer(std::string_view name);
std::vector<std::string> dtype_names();
std::vector<std::string> preset_names();
std::vector<std::string> optimizer_names();
std::vector<std::string> model_names();
/// nn::parse_model_kind, throwing Error.
nn::ModelKind parse_model(std::string_view name);

/// f.operator()<float>() or f.operator()<double>(): the one place a dtype picks a scalar type.
template <typename F>
decltype(auto) with_scalar(Dtype dtype, F&& f) {
  if (dtype == Dtype::kFloat) return f.template operator()<float>();
  return f.template operator()<double>();
}

struct RunSettings {
  std::string task{};
  nn::ModelKind model = nn::ModelKind::kHnn;
  std::uint64_t seed = 0;
  Dtype dtype = Dtype::kDouble;
  Preset preset = Preset::kPaper;
  int threads = 2;  // the engine's threads: fused kernels split each batch into row blocks
  TrainConfig train{};
  std::string data_file{};  // measured-data tasks: another file of the same format
  /// The data file's SHA-256 (data/file_digest.h), set by run_training with the file's absolute
  /// path: a run finds its data after a move and refuses another file (tasks/run.h load_run).
  std::string data_sha256{};
  /// The --steps of the run before each time it was continued (`hnn train --resume RUN --steps
  /// N`), oldest first; empty for a run trained in one go.
  std::vector<int> continued_from{};
  nlohmann::json task_settings = nlohmann::json::object();  // the task's own (Task::open)
  /// The rollout-loss keys of task_settings ("loss", "horizon", "integrator", "dt"), parsed once
  /// by resolve() (tasks/run.h): what the field tasks train with. task_settings keeps them as
  /// given, so that metrics.json and checkpoints record them as before.
  RolloutLossConfig loss{};
  /// The fit keys of task_settings ("fit", "sampler", "swim_scale", "rcond", ...), parsed once by
  /// resolve(): Adam, or sampled hidden layers with the last layer by least squares
  /// (tasks/train/fit_method.h).
  FitConfig fit{};

  /// The form metrics.json and checkpoints hold ("hidden": "200-200").
  nlohmann::json to_json() const;
};

struct RunOptions {
  std::string task{};
  nn::ModelKind model = nn::ModelKind::kHnn;
  std::uint64_t seed = 0;
  std::optional<Dtype> dtype{};  // unset: the task's (Task::default_dtype)
  Preset preset = Preset::kPaper;
  int threads = 2;
  std::optional<int> steps{}, batch_size{};
  std::optional<std::vector<int>> hidden{};  // overrides the preset's widths
  std::optional<double> learning_rate{}, weight_decay{};
  std::optional<LrSchedule> lr_schedule{};
  std::optional<OptimizerKind> optimizer{};
  std::string data_file{};
  std::string data_sha256{};  // a recorded run's (RunSettings::data_sha256)
  std::vector<int> continued_from{};
  nlohmann::json task_settings = nlohmann::json::object();
  std::filesystem::path out{};
  /// Replace the run already in `out`: its files are removed once the new run's data are read.
  bool force = false;
  bool quiet = false;
  /// Print metrics.json's content when done, instead of a summary a person reads.
  bool print_json = false;
  /// Checkpoints into out/checkpoint every this many steps (default: a tenth of the steps), at
  /// the end, and when stopped.
  std::optional<long> checkpoint_every{};
  /// Continue the run in `out` from its last checkpoint (see resume_options).
  bool resume = false;
  /// With resume: the finished run of continued_from.back() steps goes on to `steps`.
  bool continuing = false;
  /// Polled by the training loop (e.g. set on SIGINT): checkpoint and stop after the step.
  StopSignal* stop = nullptr;
};

/// The options that rebuild a run from RunSettings::to_json (metrics.json or a checkpoint's
/// settings): every setting as an override. Throws Error naming `where` and the bad key. Made,
/// with RunSettings::to_json, from the table of train_options.h (train_options_json.cpp).
RunOptions options_from_json(const nlohmann::json& settings, const std::string& where);

/// "200-200".
std::string join_widths(const std::vector<int>& widths);

}  // namespace hnn::tasks
