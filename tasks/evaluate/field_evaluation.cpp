#include "tasks/evaluate/field_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "autodiff/tape.h"
#include "nn/constrained/constrained_model.h"
#include "nn/constrained/masses.h"
#include "nn/hnn.h"
#include "tasks/evaluate/energy_errors.h"
#include "tasks/evaluate/hamiltonian_error.h"
#include "tasks/evaluate/state_errors.h"
#include "tasks/report/json_values.h"
#include "tasks/report/rollout_csv.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// The test states (at most) at which learned masses are compared on the constraints' tangent
// space.
constexpr Eigen::Index kMassErrorStates = 100;
constexpr const char* kMassesNote =
    "per body, its mass, then a rigid body's moments (nn/constrained/masses.h); the motion "
    "fixes them only where they move the system (a pinned body's mass and moments, say, only "
    "through its inertia about the pin) and up to one factor shared with the potential: "
    "masses_tangent_error compares the two on the constraints' tangent space at the test "
    "states after the best such factor (nn::tangent_mass_error), 0 for masses that move the "
    "system as its own do";

}  // namespace

double r_squared(double mse, const Batch& dxdt) {
  if (dxdt.rows() == 0) return NAN;
  const Eigen::RowVectorXd mean = dxdt.colwise().mean();
  const double variance = (dxdt.rowwise() - mean).squaredNorm() / double(dxdt.size());
  return variance > 0 ? 1 - mse / variance : NAN;
}

double dissipation_share(const nn::DynamicsModel<double>& model, const Batch& x,
                         const std::function<Batch(const Batch&)>& to_data_units) {
  const auto* hnn = dynamic_cast<const nn::Hnn<double>*>(&model);
  if (hnn == nullptr || model.config().field != nn::FieldType::kBoth || x.rows() == 0) return NAN;
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const auto parts = hnn->time_derivative_parts(ad::Var<double>::leaf(x));
  Batch solenoidal = parts.solenoidal.value(), conservative = parts.conservative.value();
  if (to_data_units) {
    solenoidal = to_data_units(solenoidal);
    conservative = to_data_units(conservative);
  }
  const double d = conservative.squaredNorm();
  return d / (solenoidal.squaredNorm() + d);
}

json learned_mass_metrics(const nn::DynamicsModel<double>& model, const Batch& x) {
  const auto* constrained = dynamic_cast<const nn::ConstrainedModel<double>*>(&model);
  const nn::ConstraintSpec& spec = model.config().constraints;
  if (constrained == nullptr || !spec.learned_masses) return json::object();
  // Coefficients c_k = 1 / (a mass or a moment); reported as the masses and moments themselves.
  const Eigen::MatrixXd c = constrained->inverse_mass_coefficients();
  const Eigen::VectorXd learned = c.row(0).cwiseInverse(),
                        truth = nn::inverse_mass_coefficients(spec).cwiseInverse();
  const nn::ConstrainedMechanics<double>& mechanics = constrained->mechanics();
  const Eigen::Index rows = std::min<Eigen::Index>(x.rows(), kMassErrorStates);
  return {{"masses_learned", std::vector<double>(learned.begin(), learned.end())},
          {"masses_true", std::vector<double>(truth.begin(), truth.end())},
          {"masses_tangent_error",
           number(nn::tangent_mass_error(spec, mechanics.mass_matrix(c), mechanics.mass(),
                                         x.topLeftCorner(rows, spec.positions())))},
          {"masses_note", kMassesNote}};
}

json rollout_metrics(const Rollouts& r, double threshold) {
  const nn::MeanStderr energy = energy_mse(r);
  const nn::MeanStderr relative_e = relative_energy_mse(r);
  const nn::MeanStderr state = state_mse(r);
  const RelativeError relative = relative_error(r, threshold);
  const RelativeError floor = relative_error_floor(r, threshold);
  const bool measured = r.measured;
  json m = {{"rollouts", r.truth.size()},
            {"rollout_t_end", r.t.empty() ? 0.0 : r.t.back()},
            {"n_rollouts", relative.count},
            {"rollout_failures", r.failures},
            {"energy_mse", measured ? json(nullptr) : number(energy.mean)},
            {"energy_mse_se", measured ? json(nullptr) : number(energy.std_error)},
            {"energy_mse_count", measured ? 0 : energy.count},
            {"energy_relative_mse", measured ? json(nullptr) : number(relative_e.mean)},
            {"energy_relative_mse_se", measured ? json(nullptr) : number(relative_e.std_error)},
            {"state_mse", number(state.mean)},
            {"state_mse_se", number(state.std_error)},
            {"state_mse_count", state.count},
            {"relative_error_geomean", number(relative.geomean)},
            {"relative_error_geomean_se", number(relative.geomean_se)},
            {"relative_error_geomean_count", relative.count},
            {"relative_error_floor", number(floor.geomean)},
            {"relative_error_floor_se", number(floor.geomean_se)},
            {"relative_error_floor_count", floor.count},
            {"valid_prediction_time_floor", number(floor.valid_time)},
            {"valid_prediction_time_floor_se", number(floor.valid_time_se)},
            {"valid_prediction_floor_censored", floor.censored},
            {"valid_prediction_time", number(relative.valid_time)},
            {"valid_prediction_time_se", number(relative.valid_time_se)},
            {"valid_prediction_time_count", relative.count},
            {"valid_prediction_threshold", threshold},
            {"valid_prediction_censored", relative.censored}};
  if (r.floor.empty()) {
    m["relative_error_floor_note"] = measured ? "no true system to perturb: the truth is measured"
                                                " data"
                                              : "no floor: the perturbation was 0";
  }
  for (const HorizonError& h : horizon_errors(r)) {
    const std::string at = fmt::format("_t{:g}", h.t);
    m["state_mse" + at] = number(h.state_mse.mean);
    m["state_mse" + at + "_se"] = number(h.state_mse.std_error);
    m["state_mse" + at + "_count"] = h.state_mse.count;
    m["relative_error" + at] = number(h.relative_error.mean);
    m["relative_error" + at + "_se"] = number(h.relative_error.std_error);
    if (!r.floor.empty()) m["relative_error_floor" + at] = number(h.floor.mean);
  }
  return m;
}

FieldEvaluation evaluate_field_model(const physics::System& truth,
                                     const nn::DynamicsModel<double>& model, const Dataset& data,
                                     const Batch& x0, const RolloutConfig& config) {
  FieldEvaluation e = evaluate_field_model(model, data, make_rollouts(truth, model, x0, config));
  e.metrics.update(hamiltonian_error_metrics(truth, learned_field(model), data.test_x));
  return e;
}

namespace {

// What the held-out points alone say: losses with standard errors, counts, R^2, and a dhnn's
// dissipation share.
json point_metrics(const nn::DynamicsModel<double>& model, const Dataset& data) {
  const nn::MeanStderr train = loss_stats(model, data.train_x, data.train_dxdt);
  const nn::MeanStderr test = loss_stats(model, data.test_x, data.test_dxdt);
  json m = {{"train_loss", number(train.mean)}, {"train_loss_se", number(train.std_error)},
            {"test_loss", number(test.mean)},   {"test_loss_se", number(test.std_error)},
            {"n_train", data.train_x.rows()},   {"n_test", data.test_x.rows()}};
  if (model.config().field == nn::FieldType::kBoth)
    m["dissipation_share"] = number(dissipation_share(model, data.test_x));
  m.update(learned_mass_metrics(model, data.test_x));
  m["train_r2"] = number(r_squared(train.mean, data.train_dxdt));
  m["test_r2"] = number(r_squared(test.mean, data.test_dxdt));
  return m;
}

}  // namespace

FieldEvaluation evaluate_field_model(const nn::DynamicsModel<double>& model, const Dataset& data,
                                     Rollouts rollouts) {
  FieldEvaluation e{.metrics = point_metrics(model, data), .rollouts = std::move(rollouts)};
  e.metrics.update(rollout_metrics(e.rollouts));
  return e;
}

FieldEvaluation evaluate_field_points(const physics::System* truth,
                                      const nn::DynamicsModel<double>& model, const Dataset& data) {
  FieldEvaluation e{.metrics = point_metrics(model, data)};
  if (truth) e.metrics.update(hamiltonian_error_metrics(*truth, learned_field(model), data.test_x));
  e.metrics["rollouts_skipped"] = kRolloutsSkipped;
  return e;
}

namespace {

// The rows of a matrix, or empty vectors for an empty matrix (no learned H).
Eigen::VectorXd row_or_empty(const Eigen::MatrixXd& m, std::size_t i) {
  return m.size() > 0 ? Eigen::VectorXd(m.row(Eigen::Index(i)).transpose()) : Eigen::VectorXd();
}

}  // namespace

std::string rollout_csv(const Rollouts& r, std::string_view model_name) {
  RolloutCsv csv(numbered_columns("x", r.truth.empty() ? 0 : r.truth[0].cols()));
  const Eigen::VectorXd t = as_vector(r.t);
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    csv.add(r.measured ? kDataSource : kTrueSource, i, t, r.truth[i],
            row_or_empty(r.true_energy, i));
    csv.add(model_name, i, t, r.pred[i], row_or_empty(r.pred_energy, i),
            row_or_empty(r.learned_h, i));
  }
  return csv.str();
}

std::string rollout_paths_csv(const physics::System& truth, const nn::DynamicsModel<double>& model,
                              std::string_view model_name, const Batch& x0,
                              const physics::Integrator& integrator, const std::vector<double>& t) {
  const physics::VectorField learned = [&model](double, const Batch& x, Batch& dxdt) {
    dxdt = model.field(x);
  };
  const physics::Trajectory true_paths = integrator.integrate(truth.field(), x0, t);
  const physics::Trajectory model_paths = integrator.integrate(learned, x0, t);
  RolloutCsv csv(numbered_columns("x", x0.cols()));
  for (Eigen::Index row = 0; row < x0.rows(); ++row) {
    const Batch true_states = true_paths.path(row), states = model_paths.path(row);
    csv.add(kTrueSource, std::size_t(row), t, true_states, truth.energy_batch(true_states));
    csv.add(model_name, std::size_t(row), t, states, truth.energy_batch(states),
            model.has_learned_energy() ? Eigen::VectorXd(model.learned_energy(states).col(0))
                                       : Eigen::VectorXd());
  }
  return csv.str();
}

}  // namespace hnn::tasks
