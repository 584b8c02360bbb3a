#pragma once
// Internal to tasks/: what a TaskRun keeps of its trained model. The model in the scalar type
// it was trained in (params.bin holds that type) and a copy in double (evaluation and rollouts
// use it: an integrator's tolerance is then not limited by float rounding of the field).

#include <filesystem>
#include <memory>
#include <variant>

#include "nn/parameter_file.h"
#include "tasks/error.h"

namespace hnn::tasks {

template <template <typename> class Model>
class TrainedModel {
 public:
  /// Keeps `model` and its copy in double.
  template <typename T>
  void keep(std::unique_ptr<Model<T>> model, std::unique_ptr<Model<double>> in_double) {
    in_double_ = std::move(in_double);
    trained_ = std::move(model);
  }

  void save(const std::filesystem::path& params) const {
    std::visit([&](const auto& model) { nn::save_parameters(params, *checked(model)); }, trained_);
  }

  const Model<double>& in_double() const { return *checked(in_double_); }

 private:
  template <typename P>
  static const P& checked(const P& model) {
    HNN_TASKS_CHECK(model != nullptr, "the run has no model yet: train or load it first");
    return model;
  }

  std::variant<std::unique_ptr<Model<float>>, std::unique_ptr<Model<double>>> trained_;
  std::unique_ptr<Model<double>> in_double_;
};

}  // namespace hnn::tasks
