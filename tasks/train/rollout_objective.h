#pragma once
// Training through an integrator (Chen et al. 2020, "Symplectic Recurrent Neural Networks"):
// from states alone, the model's field is integrated `horizon` sampling intervals from a measured
// state (rk4, leapfrog, yoshida4 or the implicit midpoint; one step per interval, or
// interval / dt sub-steps), and every predicted state is compared with the measured one. The
// loss differentiates through the steps (and, for an HNN, through its field, a second-order
// path), so no dx/dt targets are needed.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/data/dataset.h"
#include "tasks/data/stretch.h"
#include "tasks/integrate/integrator_step.h"
#include "tasks/train/objective.h"

namespace hnn::tasks {

/// The windows of horizon + 1 consecutive rows of every stretch: their first states, the
/// states after each step, and each step's length.
struct RolloutWindows {
  Batch start;
  std::vector<Batch> next;  ///< horizon matrices, windows x dim
  std::vector<Batch> step;  ///< horizon columns (windows x 1), one length per window
  Eigen::Index count() const { return start.rows(); }
};

/// Throws Error when no stretch has horizon + 1 points (naming the longest) or horizon < 1.
RolloutWindows rollout_windows(const std::vector<Stretch>& stretches, int horizon);

/// How the rollout loss measures a predicted state against the measured one: the mean squared
/// error, or the mean absolute error (Finzi et al. 2020's trajectory_mae).
enum class RolloutNorm { kL2, kL1 };

/// mean |a - b| over every element, on the tape (the l1 norm's loss).
template <typename T>
ad::Var<T> mean_absolute_error(const ad::Var<T>& a, const ad::Var<T>& b);

/// The error of predicted states against measured ones under `norm`, on the tape: nn::mse, or
/// mean_absolute_error. The one definition the training loss and the truth's loss
/// (FieldTraining::truth_loss) both use.
template <typename T>
ad::Var<T> rollout_error(RolloutNorm norm, const ad::Var<T>& predicted, const ad::Var<T>& measured);

/// "l2" or "l1"; parse throws Error naming both.
std::string_view to_string(RolloutNorm norm);
std::vector<std::string> rollout_norm_names();

/// How the rollout loss's minibatches draw windows: "independent" (uniform, with replacement,
/// as the paper's tasks draw rows) or "epochs" (shuffled epochs, Finzi et al.'s DataLoader).
std::vector<std::string> minibatch_draw_names();

/// How a run trains: its task settings "loss" (derivative or rollout), "horizon", "integrator",
/// "dt", "norm" and "minibatches", the same keys on every task that learns a field from states.
/// Parsed once, where a run's settings are resolved (tasks/run.cpp), into RunSettings::loss.
struct RolloutLossConfig {
  bool rollout = false;  ///< "loss": "rollout" (else dx/dt targets)
  int horizon = 1;       ///< sampling intervals per window
  RolloutIntegrator integrator = RolloutIntegrator::kRk4;
  double dt = 0;  ///< the step; 0: one step per sampling interval
  RolloutNorm norm = RolloutNorm::kL2;
  RowSampler::Draw minibatches = RowSampler::Draw::kWithReplacement;  ///< or kEpochs

  /// {"loss", "integrator", "horizon", "dt", ...} as metrics.json reports them.
  nlohmann::json to_json() const;
};

/// The keys above over a task's default loss (Task::default_loss): without "loss", or with the
/// default's own "loss", the keys given change the default; "loss": "derivative" over a rollout
/// default starts afresh. Throws Error (naming `task`) on a bad value, and on horizon,
/// integrator, dt or norm without the rollout loss.
RolloutLossConfig rollout_loss_config(const nlohmann::json& settings, const std::string& task,
                                      const RolloutLossConfig& defaults = {});
const std::vector<std::string>& rollout_setting_names();

/// Sub-steps per sampling interval: 1 for dt 0, else round(interval / dt), the same for every
/// interval of the windows within 1%. Throws Error naming dt and the intervals otherwise.
int rollout_substeps(const RolloutWindows& windows, double dt);

template <typename T>
class RolloutObjective : public Objective<T> {
 public:
  /// `batch_size` 0: every window. Test windows (may be empty) give the curve's test loss.
  /// Each interval is integrated in `substeps` equal steps of `integrator`.
  RolloutObjective(nn::DynamicsModel<T>& model, RolloutWindows train, RolloutWindows test,
                   Eigen::Index batch_size, const nn::AdamOptions& adam, std::uint64_t seed,
                   RolloutIntegrator integrator = RolloutIntegrator::kRk4, int substeps = 1,
                   RolloutNorm norm = RolloutNorm::kL2,
                   RowSampler::Draw minibatches = RowSampler::Draw::kWithReplacement);

  nn::Module<T>& model() override { return model_; }
  std::vector<nn::AdamGroup<T>> parameter_groups() const override {
    return {{model_.parameters(), adam_}};
  }
  RowSampler& sampler() override { return sampler_; }
  ad::Var<T> batch_loss() override;
  const nn::DynamicsModel<T>* row_model() const override { return &model_; }
  Eigen::Index gather_batch() override;
  /// The mean squared (or absolute) error of the predicted states over every step of the
  /// gathered windows' rows `block`.
  ad::Var<T> rows_loss(const nn::DynamicsModel<T>& model, ad::RowBlock block) const override;
  CurvePoint curve_point(long step, double batch_loss) const override;
  std::uint64_t data_fingerprint() const override;

 private:
  // The windows `rows` of `w` (all with nullptr) into scratch_: start states, then each step's
  // length (divided by the substeps) and target. Returns their count.
  Eigen::Index gather(const RolloutWindows& w, const std::vector<Eigen::Index>* rows) const;

  // The rows of `m` picked by `rows` (all with nullptr), scaled, into scratch_[slot], which
  // persists: a warmed-up step allocates nothing.
  void gather_rows(const Batch& m, const std::vector<Eigen::Index>* rows, double scale,
                   std::size_t slot) const;

  nn::DynamicsModel<T>& model_;
  RolloutWindows train_, test_;
  nn::AdamOptions adam_;
  RowSampler sampler_;
  RolloutIntegrator integrator_;
  int substeps_;
  RolloutNorm norm_;
  mutable std::vector<ad::Matrix<T>> scratch_;  // the gathered windows (gather's layout)
  mutable std::size_t horizon_ = 0;             // of the gathered windows
};

}  // namespace hnn::tasks
