#include "tasks/evaluate/state_errors.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>

namespace hnn::tasks {

namespace {

// Mean and standard error (sample std / sqrt(n)) of the finite values; NaN mean when none.
nn::MeanStderr mean_se(const std::vector<double>& values) {
  std::vector<double> v;
  std::copy_if(values.begin(), values.end(), std::back_inserter(v),
               [](double x) { return std::isfinite(x); });
  nn::MeanStderr out{.mean = NAN, .std_error = NAN, .count = v.size()};
  if (v.empty()) return out;
  const double n = double(v.size());
  out.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  if (v.size() > 1) {
    double ss = 0;
    for (double x : v) ss += (x - out.mean) * (x - out.mean);
    out.std_error = std::sqrt(ss / (n - 1) / n);
  }
  return out;
}

// The geometric mean of per-trajectory mean logs, with the delta method's standard error.
nn::MeanStderr geometric(const std::vector<double>& mean_logs) {
  const nn::MeanStderr log = mean_se(mean_logs);
  const double g = std::exp(log.mean);
  return {.mean = g, .std_error = g * log.std_error, .count = log.count};
}

// Mean over the measured rows (finite truth) after the start of log e, e the relative state
// error of `path` against `truth`; NaN when there is none.
double mean_log_error(const Eigen::MatrixXd& path, const Eigen::MatrixXd& truth) {
  const Eigen::VectorXd e = relative_state_error(path, truth);
  double sum = 0;
  int count = 0;
  for (Eigen::Index k = 1; k < e.size(); ++k) {
    if (!truth.row(k).allFinite()) continue;  // a missing measurement
    sum += std::log(std::max(e(k), 1e-300));
    ++count;
  }
  return count > 0 ? sum / count : NAN;
}

}  // namespace

nn::MeanStderr state_mse(const Rollouts& r) {
  std::vector<double> per_trajectory;
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    if (r.failed[i]) continue;
    double sum = 0, count = 0;
    for (Eigen::Index k = 0; k < r.truth[i].rows(); ++k) {
      if (!r.truth[i].row(k).allFinite()) continue;
      sum += (r.truth[i].row(k) - r.pred[i].row(k)).squaredNorm();
      count += double(r.truth[i].cols());
    }
    per_trajectory.push_back(count > 0 ? sum / count : NAN);
  }
  return mean_se(per_trajectory);
}

Eigen::VectorXd relative_state_error(const Eigen::MatrixXd& pred, const Eigen::MatrixXd& truth) {
  return ((pred - truth).rowwise().norm().array() /
          (pred.rowwise().norm() + truth.rowwise().norm()).array())
      .matrix();
}

namespace {

// relative_error of `paths` against r.truth, leaving out the trajectories `skip` marks.
RelativeError relative_error_of(const Rollouts& r, const std::vector<Eigen::MatrixXd>& paths,
                                const std::vector<bool>& skip, double threshold) {
  std::vector<double> logs, valid;
  int censored = 0;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    if (skip[i]) continue;
    const Eigen::MatrixXd& x = r.truth[i];
    logs.push_back(mean_log_error(paths[i], x));
    const Eigen::VectorXd error = relative_state_error(paths[i], x);
    double time = r.t.back() - r.t.front();
    bool passed = false;
    for (Eigen::Index k = 1; k < x.rows() && !passed; ++k) {
      if (x.row(k).allFinite() && !(error(k) <= threshold)) {
        time = r.t[std::size_t(k)] - r.t.front();
        passed = true;
      }
    }
    valid.push_back(time);
    censored += passed ? 0 : 1;
  }
  const nn::MeanStderr g = geometric(logs), v = mean_se(valid);
  return {.geomean = g.mean,
          .geomean_se = g.std_error,
          .valid_time = v.mean,
          .valid_time_se = v.std_error,
          .censored = censored,
          .count = int(v.count)};
}

}  // namespace

RelativeError relative_error(const Rollouts& r, double threshold) {
  return relative_error_of(r, r.pred, r.failed, threshold);
}

RelativeError relative_error_floor(const Rollouts& r, double threshold) {
  return relative_error_of(r, r.floor, std::vector<bool>(r.floor.size(), false), threshold);
}

std::vector<HorizonError> horizon_errors(const Rollouts& r) {
  std::vector<HorizonError> out;
  for (std::size_t h = 0; h < r.horizons.size(); ++h) {
    const Eigen::Index k = Eigen::Index(h);
    std::vector<double> mse, logs, floor_logs;
    for (std::size_t i = 0; i < r.truth_at.size(); ++i) {
      const Eigen::RowVectorXd x = r.truth_at[i].row(k);
      if (!x.allFinite()) continue;  // not measured at that time
      if (i < r.floor_at.size()) {
        floor_logs.push_back(
            std::log(std::max(relative_state_error(r.floor_at[i].row(k), x)(0), 1e-300)));
      }
      if (r.failed[i]) continue;
      const Eigen::RowVectorXd y = r.pred_at[i].row(k);
      mse.push_back((y - x).squaredNorm() / double(x.size()));
      logs.push_back(std::log(std::max(relative_state_error(y, x)(0), 1e-300)));
    }
    out.push_back({.t = r.horizons[h],
                   .state_mse = mean_se(mse),
                   .relative_error = geometric(logs),
                   .floor = geometric(floor_logs)});
  }
  return out;
}

Eigen::VectorXd coordinate_mse_over_time(const Rollouts& r) {
  const Eigen::Index m = Eigen::Index(r.t.size());
  Eigen::VectorXd mse = Eigen::VectorXd::Zero(m);
  int used = 0;
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    if (r.failed[i]) continue;
    mse += (r.truth[i] - r.pred[i]).array().square().rowwise().mean().matrix();
    ++used;
  }
  return used > 0 ? Eigen::VectorXd(mse / used) : Eigen::VectorXd::Constant(m, NAN);
}

}  // namespace hnn::tasks
