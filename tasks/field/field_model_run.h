#pragma once
// The part of a run that every task learning a field dx/dt = f(x) from a Dataset shares: a fresh
// model from the run's seed, training as its FieldTraining chooses, saving and loading. What a
// task evaluates and rolls out is its own (FieldRun in field_task.cpp, DataRun in
// tasks/experiments/data_task.cpp).

#include "nn/hnn.h"
#include "nn/parameter_file.h"
#include "tasks/data/dataset.h"
#include "tasks/field/field_training.h"
#include "tasks/task.h"
#include "tasks/trained_model.h"

namespace hnn::tasks {

/// How the models see their inputs (angle coordinates, input scales), as the task says, and
/// whether a baseline is given its velocities (tasks/options/model_settings.h).
struct ModelInput {
  Eigen::Index angles = 0;
  std::vector<double> input_scale{};
  bool given_velocities = false;
  nn::ConstraintSpec constraints{};  ///< the system a CHNN or CLNN is built on
};

class FieldModelRun : public TaskRun {
 public:
  TrainResult train(const LoopOptions& loop) override {
    return with_scalar(s_.dtype, [&]<typename T>() {
      std::unique_ptr<nn::DynamicsModel<T>> model = fresh_model<T>();
      const TrainResult result = training_.train(*model, data_, s_, loop);
      keep(std::move(model));
      return result;
    });
  }

  void save(const std::filesystem::path& params) const override { model_.save(params); }

  void load(const std::filesystem::path& params) override {
    with_scalar(s_.dtype, [&]<typename T>() {
      std::unique_ptr<nn::DynamicsModel<T>> model = fresh_model<T>();
      nn::load_parameters(params, *model);
      keep(std::move(model));
    });
  }

  const nn::DynamicsModel<double>& dynamics() const override { return model_.in_double(); }

 protected:
  /// Checks the batch size against the data before a run folder exists: a bad one leaves
  /// nothing behind.
  FieldModelRun(RunSettings settings, Dataset data, ModelInput input = {})
      : s_(std::move(settings)), data_(std::move(data)), input_(std::move(input)) {
    HNN_TASKS_CHECK(s_.train.batch_size <= data_.train_x.rows(),
                    "--batch {} is larger than the training set ({} rows)", s_.train.batch_size,
                    data_.train_x.rows());
  }

  RunSettings s_;
  Dataset data_;  ///< what the model trains on, in its own units
  ModelInput input_;
  FieldTraining training_{};  ///< on dx/dt targets unless a run chooses the rollout loss

  template <typename T>
  std::unique_ptr<nn::DynamicsModel<T>> fresh_model() const {
    nn::DynamicsConfig config{.model = s_.model,
                              .dim = data_.train_x.cols(),
                              .angles = input_.angles,
                              .input_scale = input_.input_scale,
                              .constraints = input_.constraints,
                              .given_velocities = input_.given_velocities};
    if (s_.model == nn::ModelKind::kDhnn) config.field = nn::FieldType::kBoth;
    config.hidden.assign(s_.train.hidden.begin(), s_.train.hidden.end());
    try {
      nn::validate(config);
    } catch (const std::invalid_argument& e) {
      throw Error(fmt::format("task '{}': {}", s_.task, e.what()));
    }
    std::mt19937_64 rng(s_.seed);
    return nn::make_model<T>(config, rng);
  }

  template <typename T>
  void keep(std::unique_ptr<nn::DynamicsModel<T>> model) {
    auto in_double = nn::cast_model<double>(*model);
    model_.keep(std::move(model), std::move(in_double));
  }

 private:
  TrainedModel<nn::DynamicsModel> model_;
};

}  // namespace hnn::tasks
