#pragma once
// Training through an integrator (Chen et al. 2020, "Symplectic Recurrent Neural Networks"):
// from states alone, the model's field is integrated `horizon` steps of RK4 from a measured
// state, one step per sampling interval, and every predicted state is compared with the
// measured one. The loss differentiates through the steps (and, for an HNN, through its field,
// a second-order path), so no dx/dt targets are needed.

#include <cstdint>
#include <vector>

#include "nn/dynamics.h"
#include "tasks/data/dataset.h"
#include "tasks/train/objective.h"

namespace hnn::tasks {

/// Stretches of states at their times (rows in time order), in the model's units.
struct Stretch {
  Eigen::VectorXd t;
  Batch x;
};

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

template <typename T>
class RolloutObjective : public Objective<T> {
 public:
  /// `batch_size` 0: every window. Test windows (may be empty) give the curve's test loss.
  RolloutObjective(nn::DynamicsModel<T>& model, RolloutWindows train, RolloutWindows test,
                   Eigen::Index batch_size, const nn::AdamOptions& adam, std::uint64_t seed);

  nn::Module<T>& model() override { return model_; }
  std::vector<ParameterGroup<T>> parameter_groups() const override {
    return {{model_.parameters(), adam_}};
  }
  RowSampler& sampler() override { return sampler_; }
  ad::Var<T> batch_loss() override;
  CurvePoint curve_point(long step, double batch_loss) const override;
  std::uint64_t data_fingerprint() const override;

 private:
  // The mean squared error of the predicted states over every step of `rows` of `w`.
  ad::Var<T> loss(const RolloutWindows& w, const std::vector<Eigen::Index>* rows) const;

  nn::DynamicsModel<T>& model_;
  RolloutWindows train_, test_;
  nn::AdamOptions adam_;
  RowSampler sampler_;
};

}  // namespace hnn::tasks
