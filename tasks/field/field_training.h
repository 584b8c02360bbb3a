#pragma once
// How a run of a field task trains, chosen in one place: on dx/dt targets (FieldObjective), or
// from the states alone through an integrator over windows of its stretches (RolloutObjective);
// either from sampled hidden layers and a solved last layer (--fit sampled+adam), or not at all
// after them (--fit sampled: nn/sampled/sampled_fit.h).
// FieldModelRun (field_model_run.h) trains with it; a run says only what differs (its stretches,
// the time unit of its model).

#include <optional>
#include <string>

#include "nn/dynamics.h"
#include "physics/system.h"
#include "tasks/data/dataset.h"
#include "tasks/data/stretch.h"
#include "tasks/evaluate/stretch_predictions.h"
#include "tasks/options.h"
#include "tasks/train/rollout_objective.h"

namespace hnn::tasks {

/// Trains `model` on `data` with FieldObjective and the training loop: steps, batch size,
/// learning rate, weight decay and record interval from `config`, the rest (checkpoints, resume,
/// stop, progress) from `loop`. Minibatches are drawn from a generator seeded with `seed`.
template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, LoopOptions loop = {});

class FieldTraining {
 public:
  /// Training on dx/dt targets.
  FieldTraining() = default;
  /// The training `loss` asks for. The rollout loss trains on windows of `stretches` (nullptr:
  /// the task's data are states without trajectories, an Error naming `task`); its dt is in
  /// units of `time_unit`, the model's time in those of the data. Checks the batch size against
  /// the windows: called before a run folder exists, a bad setting leaves nothing behind.
  FieldTraining(const RolloutLossConfig& loss, const SplitStretches* stretches,
                const TrainConfig& train, const std::string& task, double time_unit = 1);

  /// Trains `model` (fresh from the run's seed) on `data` or on the windows, with the loop's
  /// steps, schedule and record interval from `s.train`; with a sampled fit (s.fit), first
  /// samples its hidden layers and solves its last layer on data's training split (then calls
  /// loop.before_steps), and with --fit sampled stops there.
  template <typename T>
  TrainResult train(nn::DynamicsModel<T>& model, const Dataset& data, const RunSettings& s,
                    const LoopOptions& loop) const;

  const RolloutLossConfig& loss() const { return loss_; }
  /// The rollout loss that `truth` (the true system, in the model's coordinates and time unit)
  /// has through the training's integrator, steps and norm over every training window: the
  /// integrator's own error plus the data's noise, below which a model's training loss falls
  /// only by fitting the noise or undoing the integrator's error. (A mass HNN steps (q, p) where
  /// this steps the observed (q, dq/dt): for it a guide.)
  /// NaN without the rollout loss, and for the implicit midpoint.
  double truth_loss(const physics::System& truth) const;
  /// How the trained model steps along held-out stretches: as it trained through an integrator,
  /// or, trained on dx/dt, by dopri5 (the best use of a learned field).
  StretchStepping stepping() const {
    if (!loss_.rollout) return {};
    return {.integrator = loss_.integrator, .substeps = substeps_};
  }

 private:
  template <typename T>
  TrainResult train_steps(nn::DynamicsModel<T>& model, const Dataset& data, const RunSettings& s,
                          const LoopOptions& loop) const;
  template <typename T>
  TrainResult train_through_integrator(nn::DynamicsModel<T>& model, const RunSettings& s,
                                       const LoopOptions& loop) const;

  RolloutLossConfig loss_{};
  RolloutWindows train_windows_{}, test_windows_{};
  int substeps_ = 1;
};

}  // namespace hnn::tasks
