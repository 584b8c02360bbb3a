#pragma once
// A model rolled out from the first state of each held-out stretch over the stretch's own times:
// what every held-out evaluation (held_out.h) compares with the stretch. A field learned from
// dx/dt is integrated accurately (dopri5); a model trained through an integrator steps as it
// trained (tasks/integrate/integrator_step.h: the discrete map it learned).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nn/dynamics.h"
#include "physics/system.h"
#include "tasks/data/stretch.h"
#include "tasks/integrate/integrator_step.h"

namespace hnn::tasks {

/// States at a stretch's times from its first state (times x dim per stretch, batched).
using Predictor = std::function<std::vector<Batch>(const Batch& x0, const Eigen::VectorXd& t)>;

/// A field integrated by dopri5 (rtol 1e-9, atol 1e-12) with the learned rollouts' step limit
/// (kMaxLearnedSteps, rollouts.h): a stiff learned field fails here, not hangs.
Predictor dopri5_predictor(const physics::VectorField& field);

/// How a model steps along held-out stretches: dopri5 on its field, or as it trained (the
/// integrator and sub-steps per sampling interval of the rollout loss).
struct StretchStepping {
  std::optional<RolloutIntegrator> integrator{};  ///< empty: dopri5
  int substeps = 1;
  /// "dopri5 (rtol 1e-9)" or "<integrator>, <substeps> step(s) per interval".
  std::string describe() const;
};

/// The model stepped as `stepping` says. Refers to `model`.
Predictor model_predictor(const nn::DynamicsModel<double>& model, const StretchStepping& stepping);

/// The predicted paths of stretches, one per stretch (points x dim), NaN where a prediction
/// failed (a learned field that blows up), with why.
struct PredictedPaths {
  std::vector<Batch> paths;
  std::vector<std::string> failures;  ///< per stretch: empty unless its prediction failed
  int failed() const;
};

/// One path per stretch, predicted from its first state: with `batch`, one batched call when the
/// stretches share their times (the simulated tasks); else, or when the batch fails, one call per
/// stretch (a batch shares its adaptive steps: the data task predicts each alone).
PredictedPaths predict_paths(const std::vector<Stretch>& stretches, const Predictor& predict,
                             bool batch = true);

}  // namespace hnn::tasks
