#pragma once
// The pixel pendulum's training objective: the mean of ae + cc + w hnn over batches of training
// pairs drawn without replacement, in two parameter groups (the autoencoder and the latent
// model) with their own weight decay.

#include <cstdint>

#include "tasks/pixel/model.h"
#include "tasks/train/objective.h"

namespace hnn::tasks::pixel {

template <typename T>
class PixelObjective : public Objective<T> {
 public:
  PixelObjective(PixelModel<T>& model, const PixelData& data, const PixelConfig& config,
                 std::uint64_t seed);

  nn::Module<T>& model() override { return model_; }
  std::vector<nn::AdamGroup<T>> parameter_groups() const override;
  RowSampler& sampler() override { return sampler_; }
  ad::Var<T> batch_loss() override;
  /// The combined loss on the first curve_rows pairs of each split.
  CurvePoint curve_point(long step, double batch_loss) const override;
  std::uint64_t data_fingerprint() const override;

 private:
  PixelModel<T>& model_;
  const PixelData& data_;
  PixelConfig config_;
  RowSampler sampler_;
  std::vector<Eigen::Index> rows_;  // the batch's pairs (training rows follow the test rows)
};

}  // namespace hnn::tasks::pixel
