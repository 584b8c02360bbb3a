#include "tasks/evaluate/held_out.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "physics/integrator.h"
#include "tasks/evaluate/state_errors.h"
#include "tasks/report/json_values.h"
#include "tasks/report/rollout_csv.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// The held-out error along stretches looks at this many stretches of each split at most.
constexpr std::size_t kMaxStretches = 200;

// Mean, standard deviation and standard error of the finite per-stretch values.
json spread(const std::string& name, std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  const double n = double(v.size());
  double mean = v.empty() ? NAN : 0, var = 0;
  for (double x : v) mean += x / n;
  for (double x : v) var += (x - mean) * (x - mean) / std::max(1.0, n - 1);
  return {{name, number(mean)},
          {name + "_std", number(std::sqrt(var))},
          {name + "_se", number(std::sqrt(var / n))}};
}

// The first `kMaxStretches` of `all`.
std::vector<Stretch> first_stretches(const std::vector<Stretch>& all) {
  return {all.begin(), all.begin() + std::ptrdiff_t(std::min(kMaxStretches, all.size()))};
}

// The truth stepped by leapfrog, one step per sampling interval.
Predictor leapfrog_predictor(const physics::System& truth) {
  return [&truth](const Batch& x0, const Eigen::VectorXd& t) {
    const double interval = t.size() > 1 ? t(1) - t(0) : 1.0;
    const auto integrator = physics::make_integrator("leapfrog", {.dt = interval * (1 + 1e-9)});
    return integrator->integrate(truth.field(), x0, {t.data(), t.data() + t.size()}).states;
  };
}

struct Summary {
  double mean = NAN, se = NAN;
};

Summary summarise(const std::vector<double>& values) {
  Summary s;
  const auto n = double(values.size());
  if (values.empty()) return s;
  s.mean = 0;
  for (double v : values) s.mean += v / n;
  if (values.size() > 1) {
    double ss = 0;
    for (double v : values) ss += (v - s.mean) * (v - s.mean);
    s.se = std::sqrt(ss / (n - 1) / n);
  }
  return s;
}

// The predicted path `z` (model units) as the rollout r reports it, or its failure.
void in_file_units(const LearnedField& model, const Units& units, const Batch& z,
                   const std::string& failure, HeldOutRollout& r) {
  if (!failure.empty()) {
    r.failed = true;
    r.failure = fmt::format("{}: {}", r.where, failure);
    r.pred.setConstant(r.truth.rows(), r.truth.cols(), NAN);
    return;
  }
  r.pred = units.to_file(z);
  if (model.hamiltonian) r.learned_h = model.hamiltonian(z) * units.energy_to_file();
}

// The first time since the start at which the relative state error passes the threshold.
void valid_time(const Units& units, double threshold, HeldOutRollout& r) {
  const Eigen::VectorXd error =
      relative_state_error(units.to_model(r.pred), units.to_model(r.truth));
  for (Eigen::Index k = 0; k < error.size(); ++k) {
    if (!(error(k) <= threshold)) {  // NaN (a failed rollout) ends it too
      r.valid_time = r.t(k) - r.t(0);
      return;
    }
  }
  r.valid_time = r.t(r.t.size() - 1) - r.t(0);
  r.censored = true;
}

json summary_json(const std::string& name, const std::vector<double>& values) {
  const Summary s = summarise(values);
  return {{name, number(s.mean)}, {name + "_se", number(s.se)}, {name + "_count", values.size()}};
}

// Mean over the points after the start of log e, e the relative state error in the model's units.
double mean_log_error(const Units& units, const HeldOutRollout& r) {
  const Eigen::VectorXd e = relative_state_error(units.to_model(r.pred), units.to_model(r.truth));
  if (e.size() < 2) return NAN;
  return e.tail(e.size() - 1).array().max(1e-300).log().mean();
}

}  // namespace

json stretch_errors(const std::string& prefix, const std::vector<Stretch>& stretches,
                    const std::vector<Batch>& paths, int per_body) {
  std::vector<double> mse, position;
  for (std::size_t i = 0; i < stretches.size(); ++i) {
    const Batch e = paths[i] - stretches[i].x;
    const Eigen::Index n = e.cols() / 2, bodies = n / per_body;
    mse.push_back(e.rows() > 1 ? e.bottomRows(e.rows() - 1).array().square().mean() : 0.0);
    if (!std::isfinite(mse.back())) mse.back() = NAN;
    double sum = 0;
    for (Eigen::Index k = 0; k < e.rows(); ++k)
      for (Eigen::Index b = 0; b < bodies; ++b)
        sum += e.row(k).segment(b * per_body, per_body).norm();
    position.push_back(std::isfinite(sum) ? sum / double(e.rows() * bodies) : NAN);
  }
  json j = spread(prefix + "state_mse", mse);
  j.update(spread(prefix + "position_error", position));
  return j;
}

json held_out_stretch_metrics(const nn::DynamicsModel<double>& model,
                              const SplitStretches& stretches,
                              const StretchMetricsOptions& options) {
  const std::vector<Stretch> test = first_stretches(stretches.test);
  const std::vector<Stretch> train = first_stretches(stretches.train);
  const Predictor predict = model_predictor(model, options.stepping);
  const PredictedPaths on_test = predict_paths(test, predict);
  json m = stretch_errors("stretch_", test, on_test.paths, options.per_body);
  m["stretch_failures"] = on_test.failed();
  const PredictedPaths on_train = predict_paths(train, predict);
  const json fit = stretch_errors("train_stretch_", train, on_train.paths, options.per_body);
  m["train_stretch_position_error"] = fit["train_stretch_position_error"];
  m["train_stretch_state_mse"] = fit["train_stretch_state_mse"];
  m["train_stretch_failures"] = on_train.failed();
  m["stretch_predictor"] = options.stepping.describe();
  m["n_stretches"] = test.size();
  if (options.truth == nullptr) return m;
  const PredictedPaths by_leapfrog = predict_paths(test, leapfrog_predictor(*options.truth));
  const json truth = stretch_errors("truth_leapfrog_", test, by_leapfrog.paths, options.per_body);
  for (const char* key : {"position_error", "position_error_std", "state_mse"}) {
    const std::string name = std::string("truth_leapfrog_") + key;
    m[name] = truth[name];
  }
  m["truth_leapfrog_failures"] = by_leapfrog.failed();
  return m;
}

HeldOutEvaluation evaluate_held_out(const LearnedField& model, const Units& units,
                                    const std::vector<HeldOut>& held_out, Eigen::Index coordinates,
                                    const Batch& train_z, const HeldOutOptions& options) {
  HeldOutEvaluation e;
  std::vector<double> mse, valid, drift, drift_relative, logs;
  double sum = 0, count = 0, energy_sum = 0, energy_count = 0;
  int censored = 0;
  std::vector<std::string> failures;
  double h_spread = NAN;
  if (model.hamiltonian) {
    const Eigen::VectorXd h = model.hamiltonian(train_z) * units.energy_to_file();
    h_spread = std::sqrt((h.array() - h.mean()).square().sum() /
                         double(std::max<Eigen::Index>(1, h.size() - 1)));
  }
  std::vector<Stretch> in_model_units;
  for (const HeldOut& h : held_out)
    in_model_units.push_back({(h.t.array() - h.t(0)) / units.time, units.to_model(h.x)});
  const PredictedPaths z =
      predict_paths(in_model_units, dopri5_predictor(model.field), /*batch=*/false);
  for (std::size_t i = 0; i < held_out.size(); ++i) {
    const HeldOut& stretch = held_out[i];
    HeldOutRollout r{.trajectory = stretch.trajectory,
                     .where = stretch.where,
                     .t = stretch.t,
                     .truth = stretch.x};
    in_file_units(model, units, z.paths[i], z.failures[i], r);
    valid_time(units, options.threshold, r);
    if (options.truth != nullptr) {
      r.true_energy = options.truth->energy_batch(r.truth);
      if (!r.failed) r.pred_energy = options.truth->energy_batch(r.pred);
    }
    if (r.failed) {
      failures.push_back(r.failure);
    } else {
      const Eigen::ArrayXXd sq = (r.pred - r.truth).leftCols(coordinates).array().square();
      mse.push_back(sq.mean());
      sum += sq.sum();
      count += double(sq.size());
      valid.push_back(r.valid_time);
      censored += r.censored ? 1 : 0;
      logs.push_back(mean_log_error(units, r));
      if (r.pred_energy.size() > 0) {
        energy_sum += (r.pred_energy - r.true_energy).squaredNorm();
        energy_count += double(r.pred_energy.size());
      }
      if (r.learned_h.size() > 0) {
        const double d = (r.learned_h.array() - r.learned_h(0)).abs().maxCoeff();
        drift.push_back(d);
        drift_relative.push_back(d / h_spread);
      }
    }
    e.rollouts.push_back(std::move(r));
  }
  const Summary log = summarise(logs);
  const double geomean = std::exp(log.mean);
  e.metrics = {{"coordinate_mse", number(count > 0 ? sum / count : NAN)},
               {"coordinate_mse_se", number(summarise(mse).se)},
               {"coordinate_mse_count", mse.size()},
               {"relative_error_geomean", number(geomean)},
               {"relative_error_geomean_se", number(geomean * log.se)},
               {"relative_error_geomean_count", logs.size()},
               {"valid_prediction_threshold", options.threshold},
               {"valid_prediction_censored", censored},
               {"n_held_out", held_out.size()},
               {"held_out_failures", failures}};
  e.metrics.update(summary_json("valid_prediction_time", valid));
  if (options.truth != nullptr) {
    e.metrics["held_out_energy_mse"] = number(energy_count > 0 ? energy_sum / energy_count : NAN);
  }
  if (model.hamiltonian) {
    e.metrics.update(summary_json("learned_h_drift", drift));
    e.metrics.update(summary_json("learned_h_drift_relative", drift_relative));
  }
  return e;
}

std::string held_out_csv(const HeldOutEvaluation& e, const std::vector<std::string>& columns,
                         std::string_view model_name) {
  RolloutCsv csv(columns, {.times = 12});
  for (std::size_t i = 0; i < e.rollouts.size(); ++i) {
    const HeldOutRollout& r = e.rollouts[i];
    csv.add(kDataSource, i, r.t, r.truth, r.true_energy);
    csv.add(model_name, i, r.t, r.pred, r.pred_energy, r.learned_h);
  }
  return csv.str();
}

}  // namespace hnn::tasks
