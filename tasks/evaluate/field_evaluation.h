#pragma once
// The evaluation of the tasks that learn a field: losses over both splits with standard errors,
// and the energy MSE of rollouts against the true system, as the metrics of metrics.json.

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "nn/dynamics.h"
#include "physics/integrator.h"
#include "tasks/data/dataset.h"
#include "tasks/evaluate/loss_stats.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

struct FieldEvaluation {
  /// Train/test loss and energy MSE with standard errors, R^2 of each split (1 - MSE / variance
  /// of the targets), counts. (How long it took is the run's eval_seconds: tasks/run.cpp.)
  nlohmann::json metrics{};
  Rollouts rollouts{};
};

/// 1 - MSE / variance of the targets (over all components): the share of the targets' spread a
/// model explains, whatever the data's units. NaN for no targets or constant ones.
double r_squared(double mse, const Batch& dxdt);

/// For a model with a Hamiltonian and a dissipative part (a dhnn), the share of its field's
/// squared norm over the states x that is dissipation: sum |dD/dx|^2 / (sum |(dH/dp, -dH/dq)|^2
/// + sum |dD/dx|^2), each part first carried by `to_data_units` when given. NaN otherwise.
double dissipation_share(const nn::DynamicsModel<double>& model, const Batch& x,
                         const std::function<Batch(const Batch&)>& to_data_units = {});

/// For a constrained model that learns its masses (--masses learned): masses_learned and
/// masses_true (per body its mass, then a rigid body's moments), masses_tangent_error
/// (nn::tangent_mass_error at up to 100 rows of the states x: what of the masses moves the
/// system, up to the factor it shares with the potential) and masses_note. Empty for any other
/// model.
nlohmann::json learned_mass_metrics(const nn::DynamicsModel<double>& model, const Batch& x);

/// The metrics of rollouts, each with its standard error and count (over the learned rollouts
/// that did not fail): energy MSE and its relative form (energy_relative_mse, energy_errors.h;
/// both null for measured truth), state MSE, the relative error's
/// geometric mean and its floor (Note [Perturbed truth], rollouts.h), the valid prediction time
/// (until the relative error passes `threshold`) and the floor's (valid_prediction_time_floor:
/// where the system's own sensitivity ends predictability), and at each horizon
/// "state_mse_t<h>", "relative_error_t<h>" and "relative_error_floor_t<h>"; also "rollouts"
/// (asked for), "n_rollouts" (that did not fail), "rollout_t_end" and "rollout_failures".
nlohmann::json rollout_metrics(const Rollouts& rollouts, double threshold = 0.1);

/// Evaluates `model` on `data` and on rollouts from `x0` against `truth`, with the error of the
/// learned H on the test states (hamiltonian_rel_l2, tasks/evaluate/hamiltonian_error.h).
FieldEvaluation evaluate_field_model(const physics::System& truth,
                                     const nn::DynamicsModel<double>& model, const Dataset& data,
                                     const Batch& x0, const RolloutConfig& config);
/// The same with rollouts made already (along measured paths, say).
FieldEvaluation evaluate_field_model(const nn::DynamicsModel<double>& model, const Dataset& data,
                                     Rollouts rollouts);

/// metrics.json's "rollouts_skipped" for scattered states: why a run has no rollout keys.
inline constexpr const char* kRolloutsSkipped =
    "scattered states with exact derivatives, no trajectories: no rollouts, valid prediction "
    "time or reversibility; the run is judged on the held-out points (test_loss, test_r2, and "
    "hamiltonian_rel_l2 where the true H is known)";

/// Evaluates `model` on scattered states (no trajectories): the losses, counts and R^2 of both
/// splits, and with a truth (may be null) hamiltonian_rel_l2 on the test states
/// (tasks/evaluate/hamiltonian_error.h); no rollouts, and "rollouts_skipped" says so.
FieldEvaluation evaluate_field_points(const physics::System* truth,
                                      const nn::DynamicsModel<double>& model, const Dataset& data);

/// rollout.csv (tasks/report/rollout_csv.h): per trajectory the truth ("true", or "data" when
/// measured) and the model's prediction (source `model_name`).
std::string rollout_csv(const Rollouts& rollouts, std::string_view model_name);

/// `hnn rollout`'s CSV (tasks/report/rollout_csv.h): per row of x0 the true and the learned
/// paths, both with `integrator` at times t (sources "true" and `model_name`).
std::string rollout_paths_csv(const physics::System& truth, const nn::DynamicsModel<double>& model,
                              std::string_view model_name, const Batch& x0,
                              const physics::Integrator& integrator, const std::vector<double>& t);

}  // namespace hnn::tasks
