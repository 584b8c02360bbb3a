#pragma once
// The one training loop of every task: Adam with the Objective's parameter groups on its batch
// loss, the loss curve at intervals, checkpoints (train/checkpoint.h), resume from a checkpoint,
// and stop on request (train/stop.h).

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "nn/enum_names.h"
#include "tasks/report/run_folder.h"
#include "tasks/train/objective.h"
#include "tasks/train/stop.h"

namespace hnn::tasks {

struct TrainResult {
  std::vector<CurvePoint> curve{};
  double seconds = 0;  // the fit and training steps only (no data, loss-curve points, evaluation)
  /// This process's loss-curve points: each evaluates the train and test loss on up to
  /// thousands of rows, 100 times a run, so in a short run they can take longer than the steps.
  double curve_seconds = 0;
  long steps = 0;
  /// metrics.json's "fit" where the hidden layers were sampled (tasks/train/fit_method.h);
  /// null for Adam alone.
  nlohmann::json fit{};
};

/// How the learning rate moves over a run: constant, or cosine decay from the set rate at step
/// 1 towards 0 after the last step (Loshchilov & Hutter 2017, without restarts).
enum class LrSchedule { kConstant, kCosine };
inline constexpr nn::NameTable<LrSchedule, 2> kLrScheduleNames{{
    {LrSchedule::kConstant, "constant"},
    {LrSchedule::kCosine, "cosine"},
}};
std::string_view to_string(LrSchedule schedule);
/// Inverse of to_string; throws std::invalid_argument naming the valid values.
LrSchedule parse_lr_schedule(std::string_view name);
/// The factor on the learning rate at `step` (1-based) of `steps`.
double lr_factor(LrSchedule schedule, long step, long steps);

struct LoopOptions {
  long steps = 0;
  LrSchedule lr_schedule = LrSchedule::kConstant;
  long record_every = 0;  // loss-curve interval; 0: about 100 points
  bool quiet = false;     // no progress output
  std::string label = "train";
  std::function<void(long step)> on_record{};  // after each loss-curve point
  /// Checkpoints (train/checkpoint.h) go to this folder every `checkpoint_every` steps (0: a
  /// tenth of the steps), at the last step, and when stopped; none when it is empty.
  std::filesystem::path checkpoint_dir{};
  long checkpoint_every = 0;
  /// Continue from the checkpoint in checkpoint_dir instead of starting at step 0.
  bool resume = false;
  /// With resume: the steps of the finished run the checkpoint is of, when this run goes on past
  /// them to `steps` (0: the checkpoint is of a run of `steps`).
  long checkpoint_steps = 0;
  /// The run's settings, stored in every checkpoint (for `hnn train --resume`); with a sampled
  /// fit, its report under "fit" (what the run keeps when resumed).
  nlohmann::json run_settings{};
  /// Called once by a run that samples its hidden layers first (FieldTraining), after sampling
  /// and before anything is written: the run folder is made there, so that a fit that fails
  /// leaves none (tasks/run.cpp).
  std::function<void()> before_steps{};
  /// Polled after every step: when requested, training checkpoints and throws
  /// TrainingInterrupted.
  StopSignal* stop = nullptr;
};

/// Trains the objective's model in place. The same seed gives the same run, and a run resumed
/// from a checkpoint ends with the same parameters, bit for bit, as one never stopped. Throws
/// TrainingDiverged at the first step whose loss is not finite (the last checkpoint is kept).
template <typename T>
TrainResult train(Objective<T>& objective, const LoopOptions& options);

}  // namespace hnn::tasks
