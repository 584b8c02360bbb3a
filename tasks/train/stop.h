#pragma once
// How a training run stops before its last step: on request (a StopSignal, e.g. from Ctrl-C,
// then TrainingInterrupted with a checkpoint written) or because it diverged (TrainingDiverged,
// the last good checkpoint kept). Both are a TrainingStopped at a step, so a caller may catch
// either one or both.

#include <atomic>
#include <stdexcept>
#include <string>

namespace hnn::tasks {

/// Training stopped after `step()` before its last step.
class TrainingStopped : public std::runtime_error {
 public:
  TrainingStopped(const std::string& message, long step)
      : std::runtime_error(message), step_(step) {}
  long step() const { return step_; }

 private:
  long step_;
};

/// Training stopped because the loss, its gradient or the parameters became NaN or infinite.
class TrainingDiverged : public TrainingStopped {
 public:
  using TrainingStopped::TrainingStopped;
  /// The one wording of every such stop: "training diverged at step N: <reason><where>", where
  /// `where` says which checkpoint is kept.
  static TrainingDiverged at(long step, const std::string& reason, const std::string& where) {
    return {"training diverged at step " + std::to_string(step) + ": " + reason + where, step};
  }
};

/// Training stopped on request (StopSignal) after `step()`, with a checkpoint written.
class TrainingInterrupted : public TrainingStopped {
 public:
  using TrainingStopped::TrainingStopped;
};

/// Asks a training loop to stop after its current step. Set from a signal handler, so it holds
/// lock-free atomics only. `armed` is true while a loop polls `requested`: a handler can fall
/// back to the signal's default action when nothing would.
struct StopSignal {
  std::atomic<bool> armed{false};
  std::atomic<bool> requested{false};
};

}  // namespace hnn::tasks
