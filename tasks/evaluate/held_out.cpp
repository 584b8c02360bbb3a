#include "tasks/evaluate/held_out.h"

#include <fmt/format.h>

#include <cmath>

#include "physics/integrator.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

namespace {

// As the energy rollouts (rollouts.cpp): a field that needs more steps than this is reported
// as failed rather than integrated for hours.
constexpr long kMaxLearnedSteps = 100'000;

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

// Rolls the model out in its own units from the stretch's first state at its own times.
void roll_out(const LearnedField& model, const Units& units, HeldOutRollout& r) {
  const Batch z0 = units.to_model(Batch(r.truth.topRows(1)));
  std::vector<double> t(std::size_t(r.t.size()));
  for (Eigen::Index k = 0; k < r.t.size(); ++k) t[std::size_t(k)] = (r.t(k) - r.t(0)) / units.time;
  const auto dopri = physics::make_integrator(
      "dopri5", {.rtol = 1e-9, .atol = 1e-12, .max_steps = kMaxLearnedSteps});
  try {
    const Batch z = dopri->integrate(model.field, z0, t).path(0);
    r.pred = units.to_file(z);
    if (model.hamiltonian) r.learned_h = model.hamiltonian(z) * units.energy_to_file();
  } catch (const physics::IntegrationError& e) {
    r.failed = true;
    r.failure = fmt::format("{}: {}", r.where, e.what());
    r.pred.setConstant(r.truth.rows(), r.truth.cols(), NAN);
  }
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

nlohmann::json summary_json(const std::string& name, const std::vector<double>& values) {
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
  for (const HeldOut& stretch : held_out) {
    HeldOutRollout r{.trajectory = stretch.trajectory,
                     .where = stretch.where,
                     .t = stretch.t,
                     .truth = stretch.x};
    roll_out(model, units, r);
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

namespace {

double at(const Eigen::VectorXd& v, Eigen::Index k) { return v.size() > k ? v(k) : NAN; }

}  // namespace

std::string held_out_csv(const HeldOutEvaluation& e) {
  const Eigen::Index dim = e.rollouts.empty() ? 0 : e.rollouts[0].truth.cols();
  std::string csv = "traj,t";
  for (const char* which : {"true", "pred"})
    for (Eigen::Index c = 0; c < dim; ++c) csv += fmt::format(",{}_{}", which, c);
  csv += ",true_energy,pred_energy,learned_h\n";
  for (std::size_t i = 0; i < e.rollouts.size(); ++i) {
    const HeldOutRollout& r = e.rollouts[i];
    for (Eigen::Index k = 0; k < r.t.size(); ++k) {
      csv += fmt::format("{},{:.12g}", i, r.t(k));
      for (Eigen::Index c = 0; c < dim; ++c) csv += "," + csv_cell(r.truth(k, c));
      for (Eigen::Index c = 0; c < dim; ++c) csv += "," + csv_cell(r.pred(k, c));
      csv += fmt::format(",{},{},{}\n", csv_cell(at(r.true_energy, k)),
                         csv_cell(at(r.pred_energy, k)), csv_cell(at(r.learned_h, k)));
    }
  }
  return csv;
}

}  // namespace hnn::tasks
