#pragma once
// The shared training loop: Adam on the mean squared error of a model's time derivative, full
// batch or minibatch, with the loss curve recorded at intervals.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/task.h"

namespace hnn::tasks {

struct CurvePoint {
  long step;
  double train_loss, test_loss;
};

struct TrainResult {
  std::vector<CurvePoint> curve;
  double seconds = 0;  // the training steps only (no data, no loss-curve points, no evaluation)
  long steps = 0;
};

/// Training stopped because the loss became NaN or infinite.
class TrainingDiverged : public std::runtime_error {
 public:
  TrainingDiverged(const std::string& message, long step)
      : std::runtime_error(message), step_(step) {}
  long step() const { return step_; }

 private:
  long step_;
};

/// Training stopped on request (StopSignal) after `step()`, with a checkpoint written.
class TrainingInterrupted : public std::runtime_error {
 public:
  TrainingInterrupted(const std::string& message, long step)
      : std::runtime_error(message), step_(step) {}
  long step() const { return step_; }

 private:
  long step_;
};

/// Asks a training loop to stop after its current step. Set from a signal handler, so it holds
/// lock-free atomics only. `armed` is true while a loop polls `requested`: a handler can fall
/// back to the signal's default action when nothing would.
struct StopSignal {
  std::atomic<bool> armed{false};
  std::atomic<bool> requested{false};
};

struct TrainHooks {
  bool quiet = false;                          // no progress output
  std::string label = "train";                 // progress label
  std::function<void(long step)> on_record{};  // after each loss-curve point (checkpoints)
  /// Checkpoints (tasks/train_checkpoint.h) go to this folder every `checkpoint_every` steps, at
  /// the last step, and when stopped; none when it is empty.
  std::filesystem::path checkpoint_dir{};
  long checkpoint_every = 0;
  /// Continue from the checkpoint in checkpoint_dir instead of starting at step 0.
  bool resume = false;
  /// The run's settings, stored in every checkpoint (for `hnn train --resume`).
  nlohmann::json run_settings{};
  /// Polled after every step: when requested, training checkpoints and throws
  /// TrainingInterrupted.
  StopSignal* stop = nullptr;
};

/// Trains `model` in place. Minibatches are drawn from a generator seeded with `seed`, so the
/// same seed gives the same run, and a run resumed from a checkpoint ends with the same
/// parameters, bit for bit, as one never stopped. Throws TrainingDiverged at the first step whose
/// loss is not finite (the last checkpoint, if any, is kept).
template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, const TrainHooks& hooks = {});

/// Mean squared error of the model's field on (x, dxdt), computed in chunks without a graph.
template <typename T>
double field_mse(const nn::DynamicsModel<T>& model, const Batch& x, const Batch& dxdt);

}  // namespace hnn::tasks
