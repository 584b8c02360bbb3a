#pragma once
// The held-out evaluator: a model predicted from the first state of each held-out stretch over
// the stretch's own times (stretch_predictions.h) and compared with the stretch. The tasks on
// simulated trajectories report SRNN's errors (held_out_stretch_metrics); the data task, whose
// model trains in standardised units, reports in the file's units (evaluate_held_out).

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "tasks/data/measured_dataset.h"
#include "tasks/data/stretch.h"
#include "tasks/data/units.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/evaluate/stretch_predictions.h"

namespace hnn::tasks {

/// The held-out error of predicted paths against the stretches: state MSE over the points after
/// the start, and the position error (SRNN's measure: the Euclidean distance of each body's
/// position, averaged over the bodies and over every sampled time, the start included), each
/// with `_std` and `_se` over the stretches; keys start with `prefix`.
nlohmann::json stretch_errors(const std::string& prefix, const std::vector<Stretch>& stretches,
                              const std::vector<Batch>& paths, int per_body);

struct StretchMetricsOptions {
  int per_body = 1;                        ///< position coordinates per body
  StretchStepping stepping{};              ///< how the model steps
  const physics::System* truth = nullptr;  ///< the true system, when there is one
};

/// The model along at most 200 test stretches (stretch_errors with prefix "stretch_", and
/// "stretch_failures", "stretch_predictor", "n_stretches"), the same on as many training
/// stretches ("train_stretch_position_error", "train_stretch_state_mse",
/// "train_stretch_failures": the gap to the test figure is what generalisation costs), and with
/// a truth, the truth by leapfrog with one step per interval ("truth_leapfrog_..."): what the
/// sampling alone costs a symplectic integrator.
nlohmann::json held_out_stretch_metrics(const nn::DynamicsModel<double>& model,
                                        const SplitStretches& stretches,
                                        const StretchMetricsOptions& options);

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

/// The data task's: `model` works in `units` (model.field(z) = dz/dt' with z =
/// units.to_model(x)) and is integrated there by dopri5, each stretch alone, so that tolerances
/// mean the same at any data scale; errors are reported in the file's units. `train_z` (the
/// training states in the model's units) sets the scale of the learned H.
HeldOutEvaluation evaluate_held_out(const LearnedField& model, const Units& units,
                                    const std::vector<HeldOut>& held_out, Eigen::Index coordinates,
                                    const Batch& train_z, const HeldOutOptions& options = {});

/// rollout.csv of a data run (tasks/report/rollout_csv.h): per held-out stretch, at its own
/// times, the data ("data") and the prediction (source `model_name`), with the state's
/// `columns`; the energy column is empty without a known H.
std::string held_out_csv(const HeldOutEvaluation& evaluation,
                         const std::vector<std::string>& columns, std::string_view model_name);

}  // namespace hnn::tasks
