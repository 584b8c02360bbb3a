#pragma once
// Evaluation without a known H: the learned model rolled out from the first state of each
// held-out stretch over the stretch's own times and compared with the measured states. The
// rollouts are integrated in the model's units (so tolerances mean the same at any data scale)
// and reported in the file's.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tasks/data/measured_dataset.h"
#include "tasks/data/units.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

struct HeldOutRollout {
  double trajectory = 0;
  std::string where{};    ///< the stretch's first row in the file
  Eigen::VectorXd t{};    ///< the file's times
  Batch truth{}, pred{};  ///< measured and predicted states, file units (pred NaN when failed)
  Eigen::VectorXd learned_h{};                   ///< the model's H along pred, file units; or empty
  Eigen::VectorXd true_energy{}, pred_energy{};  ///< a known H of truth and pred; or empty
  double valid_time = 0;                         ///< time since the start until the error threshold
  bool censored = false;                         ///< the error never passed it: a lower bound
  bool failed = false;
  std::string failure{};
};

struct HeldOutOptions {
  /// The relative state error ||x^ - x|| / (||x^|| + ||x||), in the model's units, that ends
  /// the valid prediction time.
  double threshold = 0.1;
  const physics::System* truth = nullptr;  ///< a known H, for the energy columns
};

struct HeldOutEvaluation {
  std::vector<HeldOutRollout> rollouts;
  /// coordinate_mse (file units, over every time and coordinate), valid_prediction_time (file
  /// time, mean over stretches), relative_error_geomean (the geometric mean of the relative
  /// state error in the model's units after each start; its standard error by the delta
  /// method), learned_h_drift (max |H(t) - H(0)| per stretch, mean, file units) and
  /// learned_h_drift_relative (that over the spread of H on the training states), each with a
  /// standard error over stretches when there are several and a count; with a known H,
  /// held_out_energy_mse: (H(measured) - H(predicted))^2 over every held-out point (the
  /// dissipative-HNN paper's energy MSE along the test trajectory).
  nlohmann::json metrics;
};

/// `model` works in `units`: model.field(z) = dz/dt' with z = units.to_model(x).
/// `train_z` (the training states in the model's units) sets the scale of the learned H.
HeldOutEvaluation evaluate_held_out(const LearnedField& model, const Units& units,
                                    const std::vector<HeldOut>& held_out, Eigen::Index coordinates,
                                    const Batch& train_z, const HeldOutOptions& options = {});

/// rollout.csv of a data run: traj,t,true_0..,pred_0..,true_energy,pred_energy,learned_h, each
/// held-out stretch at its own times (true_energy and pred_energy empty without a known H).
std::string held_out_csv(const HeldOutEvaluation& evaluation);

}  // namespace hnn::tasks
