#pragma once
// The objective of the tasks that learn a field from states and their derivatives: the mean
// squared error of the model's time derivative against dx/dt, over the full training set or
// minibatches drawn with replacement.

#include <cstdint>

#include "nn/dynamics.h"
#include "tasks/data/dataset.h"
#include "tasks/train/objective.h"

namespace hnn::tasks {

template <typename T>
class FieldObjective : public Objective<T> {
 public:
  /// `batch_size` 0: the full batch. The data are copied (cast to T) once.
  FieldObjective(nn::DynamicsModel<T>& model, const Dataset& data, Eigen::Index batch_size,
                 const nn::AdamOptions& adam, std::uint64_t seed);

  nn::Module<T>& model() override { return model_; }
  std::vector<nn::AdamGroup<T>> parameter_groups() const override {
    return {{model_.parameters(), adam_}};
  }
  RowSampler& sampler() override { return sampler_; }
  ad::Var<T> batch_loss() override;
  const nn::DynamicsModel<T>* row_model() const override { return &model_; }
  Eigen::Index gather_batch() override;
  ad::Var<T> rows_loss(const nn::DynamicsModel<T>& model, ad::RowBlock block) const override;
  CurvePoint curve_point(long step, double batch_loss) const override;
  std::uint64_t data_fingerprint() const override { return fingerprint(data_); }

 private:
  nn::DynamicsModel<T>& model_;
  const Dataset& data_;
  nn::AdamOptions adam_;
  RowSampler sampler_;
  ad::Matrix<T> x_, dxdt_, batch_x_, batch_dxdt_;
};

/// Mean squared error of the model's field on (x, dxdt), computed in chunks without a graph.
template <typename T>
double field_mse(const nn::DynamicsModel<T>& model, const Batch& x, const Batch& dxdt);

}  // namespace hnn::tasks
