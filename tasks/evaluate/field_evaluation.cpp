#include "tasks/evaluate/field_evaluation.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "autodiff/tape.h"
#include "nn/hnn.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

using nlohmann::json;

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

json rollout_metrics(const Rollouts& r, double threshold) {
  const nn::MeanStderr energy = energy_mse(r);
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
  const auto start = std::chrono::steady_clock::now();
  FieldEvaluation e = evaluate_field_model(model, data, make_rollouts(truth, model, x0, config));
  e.metrics["eval_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return e;
}

FieldEvaluation evaluate_field_model(const nn::DynamicsModel<double>& model, const Dataset& data,
                                     Rollouts rollouts) {
  const auto start = std::chrono::steady_clock::now();
  const nn::MeanStderr train = loss_stats(model, data.train_x, data.train_dxdt);
  const nn::MeanStderr test = loss_stats(model, data.test_x, data.test_dxdt);
  FieldEvaluation e{.rollouts = std::move(rollouts)};
  e.metrics = {{"train_loss", number(train.mean)}, {"train_loss_se", number(train.std_error)},
               {"test_loss", number(test.mean)},   {"test_loss_se", number(test.std_error)},
               {"n_train", data.train_x.rows()},   {"n_test", data.test_x.rows()}};
  e.metrics.update(rollout_metrics(e.rollouts));
  if (model.config().field == nn::FieldType::kBoth)
    e.metrics["dissipation_share"] = number(dissipation_share(model, data.test_x));
  e.metrics["train_r2"] = number(r_squared(train.mean, data.train_dxdt));
  e.metrics["test_r2"] = number(r_squared(test.mean, data.test_dxdt));
  e.metrics["eval_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return e;
}

namespace {

std::string rollout_row(const Rollouts& r, std::size_t i, std::size_t k) {
  const Eigen::Index row = Eigen::Index(k), traj = Eigen::Index(i);
  std::string line = fmt::format("{},{:.9g}", i, r.t[k]);
  for (Eigen::Index c = 0; c < r.truth[i].cols(); ++c) line += "," + csv_cell(r.truth[i](row, c));
  for (Eigen::Index c = 0; c < r.pred[i].cols(); ++c) line += "," + csv_cell(r.pred[i](row, c));
  line += "," + csv_cell(r.true_energy(traj, row)) + "," + csv_cell(r.pred_energy(traj, row)) + ",";
  if (r.learned_h.size() > 0) line += csv_cell(r.learned_h(traj, row));
  return line + "\n";
}

}  // namespace

std::string rollout_csv(const Rollouts& r) {
  const Eigen::Index dim = r.truth.empty() ? 0 : r.truth[0].cols();
  std::string csv = "traj,t";
  for (const char* which : {"true", "pred"})
    for (Eigen::Index k = 0; k < dim; ++k) csv += fmt::format(",{}_{}", which, k);
  csv += ",true_energy,pred_energy,learned_h\n";
  for (std::size_t i = 0; i < r.truth.size(); ++i)
    for (std::size_t k = 0; k < r.t.size(); ++k) csv += rollout_row(r, i, k);
  return csv;
}

namespace {

// One CSV block per source: source,traj,t,x_0..x_{d-1},energy,learned_h
void append_paths(std::string& csv, std::string_view source, const physics::Trajectory& path,
                  const physics::System& truth, const nn::Hnn<double>* hnn) {
  for (Eigen::Index row = 0; row < path.states.front().rows(); ++row) {
    const Eigen::MatrixXd states = path.path(row);
    const Eigen::VectorXd energy = truth.energy_batch(physics::Batch(states));
    Eigen::VectorXd h;
    if (hnn) h = hnn->energy(physics::Batch(states)).col(0);
    for (Eigen::Index k = 0; k < states.rows(); ++k) {
      csv += fmt::format("{},{},{:.9g}", source, row, path.t[std::size_t(k)]);
      for (Eigen::Index c = 0; c < states.cols(); ++c) csv += fmt::format(",{:.12g}", states(k, c));
      csv += fmt::format(",{:.12g},{}\n", energy(k), hnn ? fmt::format("{:.12g}", h(k)) : "");
    }
  }
}

}  // namespace

std::string rollout_paths_csv(const physics::System& truth, const nn::DynamicsModel<double>& model,
                              std::string_view model_name, const Batch& x0,
                              const physics::Integrator& integrator, const std::vector<double>& t) {
  const physics::VectorField learned = [&model](double, const Batch& x, Batch& dxdt) {
    dxdt = model.field(x);
  };
  std::string csv = "source,traj,t";
  for (Eigen::Index c = 0; c < x0.cols(); ++c) csv += fmt::format(",x_{}", c);
  csv += ",energy,learned_h\n";
  append_paths(csv, "true", integrator.integrate(truth.field(), x0, t), truth, nullptr);
  append_paths(csv, model_name, integrator.integrate(learned, x0, t), truth,
               dynamic_cast<const nn::Hnn<double>*>(&model));
  return csv;
}

}  // namespace hnn::tasks
