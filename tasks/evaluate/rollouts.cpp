#include "tasks/evaluate/rollouts.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <random>
#include <stdexcept>

#include "nn/hnn.h"
#include "nn/lnn.h"
#include "physics/integrator.h"
#include "physics/types.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

constexpr Eigen::Index kChunk = 4096;
constexpr int kSplits = 5;
// A learned rollout taking more steps than this is reported as failed (with the time reached)
// rather than left to run for hours: a badly trained field can be stiff enough to need the
// integrator's default limit of 1e8 steps. True fields keep that default.
constexpr long kMaxLearnedSteps = 100'000;

Eigen::MatrixXd integrate_one(const physics::VectorField& field, const Eigen::RowVectorXd& x0,
                              const std::vector<double>& t, const RolloutConfig& config, long* nfev,
                              long max_steps = physics::IntegratorOptions{}.max_steps) {
  const auto dopri = physics::make_integrator(
      "dopri5", {.rtol = config.rtol, .atol = config.atol, .max_steps = max_steps});
  const physics::Trajectory path = dopri->integrate(field, Batch(x0), t);
  if (nfev) *nfev += path.stats.nfev;
  return path.path(0);
}

// The grid's times and the horizons in one increasing list, and where each of them is in it.
struct Times {
  std::vector<double> all;
  std::vector<std::size_t> grid, horizons;
};

Times merge_times(const std::vector<double>& grid, const std::vector<double>& horizons) {
  Times out;
  out.all = grid;
  const double end = grid.empty() ? 0.0 : grid.back();
  const auto same = [&](double a, double b) { return std::abs(a - b) <= 1e-12 * (1 + end); };
  for (double h : horizons) {
    HNN_TASKS_CHECK(h > 0 && h <= end * (1 + 1e-12),
                    "rollouts: horizon {} is outside the rollout's span (0, {}]", h, end);
    if (std::none_of(out.all.begin(), out.all.end(), [&](double t) { return same(t, h); }))
      out.all.push_back(h);
  }
  std::sort(out.all.begin(), out.all.end());
  const auto at = [&](double t) {
    return std::size_t(
        std::find_if(out.all.begin(), out.all.end(), [&](double a) { return same(a, t); }) -
        out.all.begin());
  };
  for (double t : grid) out.grid.push_back(at(t));
  for (double h : horizons) out.horizons.push_back(at(h));
  return out;
}

// The rows of `path` at the given indices.
Eigen::MatrixXd pick(const Eigen::MatrixXd& path, const std::vector<std::size_t>& rows) {
  Eigen::MatrixXd out(Eigen::Index(rows.size()), path.cols());
  for (std::size_t k = 0; k < rows.size(); ++k)
    out.row(Eigen::Index(k)) = path.row(Eigen::Index(rows[k]));
  return out;
}

using EnergyFn = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;

// The learned rollout from x0 as the next trajectory of r: its path, energy and learned H, or a
// failure (NaN path) with the time reached.
void add_learned(Rollouts& r, const LearnedField& learned, const Eigen::RowVectorXd& x0,
                 const Times& times, const RolloutConfig& config, const EnergyFn& energy) {
  const Eigen::Index i = Eigen::Index(r.pred.size());
  try {
    const Eigen::MatrixXd path =
        integrate_one(learned.field, x0, times.all, config, &r.nfev, kMaxLearnedSteps);
    r.pred.push_back(pick(path, times.grid));
    r.pred_at.push_back(pick(path, times.horizons));
    r.failed.push_back(false);
    if (energy) r.pred_energy.row(i) = energy(r.pred.back()).transpose();
    if (learned.hamiltonian)
      r.learned_h.row(i) = learned.hamiltonian(Batch(r.pred.back())).transpose();
  } catch (const std::exception& e) {
    // An integration that gives up, or a learned field that cannot be evaluated on the way (an
    // LNN whose mass matrix turns singular): the rollout failed there, the others go on.
    r.pred.push_back(Eigen::MatrixXd::Constant(Eigen::Index(times.grid.size()), x0.size(), NAN));
    r.pred_at.push_back(
        Eigen::MatrixXd::Constant(Eigen::Index(times.horizons.size()), x0.size(), NAN));
    r.failed.push_back(true);
    r.failures.push_back(fmt::format("trajectory {}: {}", i, e.what()));
  }
}

}  // namespace

nn::MeanStderr loss_stats(const nn::DynamicsModel<double>& model, const Batch& x,
                          const Batch& dxdt) {
  return loss_stats(learned_field(model).field, x, dxdt);
}

nn::MeanStderr loss_stats(const physics::VectorField& field, const Batch& x, const Batch& dxdt) {
  if (x.rows() == 0) throw std::invalid_argument("loss_stats: no points");
  Batch errors(x.rows(), x.cols());  // squared error of every component of every point
  Batch pred;
  for (Eigen::Index start = 0; start < x.rows(); start += kChunk) {
    const Eigen::Index n = std::min(kChunk, x.rows() - start);
    field(0.0, x.middleRows(start, n), pred);
    errors.middleRows(start, n) = (pred - dxdt.middleRows(start, n)).array().square().matrix();
  }
  // The reference's error bar: torch's std (n - 1) over all N x D squared errors, / sqrt(N).
  const double mean = errors.mean(), count = double(errors.size());
  const double variance = count > 1 ? (errors.array() - mean).square().sum() / (count - 1) : 0.0;
  return {mean, std::sqrt(variance / double(x.rows())), std::size_t(x.rows())};
}

LearnedField learned_field(const nn::DynamicsModel<double>& model) {
  LearnedField learned{
      .field = [&model](double, const Batch& x, Batch& dxdt) { dxdt = model.field(x); }};
  const auto* hnn = dynamic_cast<const nn::Hnn<double>*>(&model);
  if (hnn != nullptr && model.config().field != nn::FieldType::kConservative)
    learned.hamiltonian = [hnn](const Batch& x) -> Eigen::VectorXd {
      return hnn->energy(x).col(0);
    };
  // An LNN's conserved quantity: its learned energy v · dL/dv - L.
  if (const auto* lnn = dynamic_cast<const nn::Lnn<double>*>(&model))
    learned.hamiltonian = [lnn](const Batch& x) -> Eigen::VectorXd {
      return lnn->energy(x).col(0);
    };
  return learned;
}

Rollouts make_rollouts(const physics::System& truth, const nn::DynamicsModel<double>& model,
                       const Batch& x0, const RolloutConfig& config) {
  return make_rollouts(truth, learned_field(model), x0, config);
}

Rollouts make_rollouts(const physics::System& truth, const LearnedField& learned, const Batch& x0,
                       const RolloutConfig& config) {
  Rollouts r;
  r.t = physics::linspace(0.0, config.t_end, config.points);
  r.horizons = config.horizons;
  const Times times = merge_times(r.t, config.horizons);
  const Eigen::Index n = x0.rows(), m = Eigen::Index(r.t.size());
  r.true_energy.setConstant(n, m, NAN);
  r.pred_energy.setConstant(n, m, NAN);
  if (learned.hamiltonian) r.learned_h.setConstant(n, m, NAN);
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd path =
        integrate_one(truth.field(), x0.row(i), times.all, config, nullptr);
    r.truth.push_back(pick(path, times.grid));
    r.truth_at.push_back(pick(path, times.horizons));
    r.true_energy.row(i) = truth.energy_batch(Batch(r.truth.back())).transpose();
    if (config.perturbation > 0) {
      Eigen::RowVectorXd start = x0.row(i);
      for (Eigen::Index c = 0; c < start.size(); ++c) {
        const double scale =
            config.perturbation_scale.empty() ? 1.0 : config.perturbation_scale[std::size_t(c)];
        start(c) += config.perturbation * scale * normal(rng);
      }
      const Eigen::MatrixXd moved = integrate_one(truth.field(), start, times.all, config, nullptr);
      r.floor.push_back(pick(moved, times.grid));
      r.floor_at.push_back(pick(moved, times.horizons));
    }
    add_learned(r, learned, x0.row(i), times, config, [&](const Eigen::MatrixXd& states) {
      return Eigen::VectorXd(truth.energy_batch(Batch(states)));
    });
  }
  return r;
}

Rollouts follow_measured(const std::vector<Eigen::MatrixXd>& measured, const LearnedField& learned,
                         const RolloutConfig& config) {
  Rollouts r;
  r.measured = true;
  r.t = physics::linspace(0.0, config.t_end, config.points);
  // Measurements exist at the grid's times only: each horizon moves to the nearest of them.
  for (double h : config.horizons) {
    const auto k = std::size_t(std::lround(h / config.t_end * (config.points - 1)));
    r.horizons.push_back(r.t[std::min(k, r.t.size() - 1)]);
  }
  const Times times = merge_times(r.t, r.horizons);
  const Eigen::Index n = Eigen::Index(measured.size()), m = Eigen::Index(r.t.size());
  r.true_energy.setConstant(n, m, NAN);
  r.pred_energy.setConstant(n, m, NAN);
  if (learned.hamiltonian) r.learned_h.setConstant(n, m, NAN);
  for (const Eigen::MatrixXd& path : measured) {
    HNN_TASKS_CHECK(path.rows() == m && path.row(0).allFinite(),
                    "follow_measured: a path of {} rows for {} times, or without its start",
                    path.rows(), m);
    r.truth.push_back(path);
    r.truth_at.push_back(pick(path, times.horizons));
    add_learned(r, learned, path.row(0), times, config, nullptr);
  }
  return r;
}

nn::MeanStderr energy_mse(const Rollouts& r) {
  std::vector<double> per_trajectory;
  for (std::size_t i = 0; i < r.failed.size(); ++i) {
    if (r.failed[i]) continue;
    const Eigen::Index row = Eigen::Index(i);
    per_trajectory.push_back((r.true_energy.row(row) - r.pred_energy.row(row)).squaredNorm() /
                             double(r.true_energy.cols()));
  }
  nn::MeanStderr out;
  out.count = per_trajectory.size();
  if (per_trajectory.empty()) {
    out.mean = out.std_error = NAN;
    return out;
  }
  double sum = 0;
  for (double v : per_trajectory) sum += v;
  out.mean = sum / double(per_trajectory.size());
  // Standard error from the spread of the means of 5 interleaved splits.
  const int splits = std::min<int>(kSplits, int(per_trajectory.size()));
  Eigen::VectorXd means = Eigen::VectorXd::Zero(splits), counts = Eigen::VectorXd::Zero(splits);
  for (std::size_t i = 0; i < per_trajectory.size(); ++i) {
    means(int(i % splits)) += per_trajectory[i];
    counts(int(i % splits)) += 1;
  }
  means = means.cwiseQuotient(counts);
  const double spread = std::sqrt((means.array() - means.mean()).square().mean());
  out.std_error = splits > 1 ? spread / std::sqrt(double(splits)) : NAN;
  return out;
}

nn::MeanStderr energy_error_at_end(const Rollouts& r, double scale) {
  std::vector<double> errors;
  const Eigen::Index end = r.true_energy.cols() - 1;
  for (std::size_t i = 0; i < r.failed.size(); ++i) {
    const Eigen::Index row = Eigen::Index(i);
    if (!r.failed[i])
      errors.push_back(std::abs(r.pred_energy(row, end) - r.true_energy(row, end)) / scale);
  }
  if (errors.empty()) return {.mean = NAN, .std_error = NAN, .count = 0};
  return nn::mean_and_stderr<double>(Eigen::VectorXd(
      Eigen::Map<const Eigen::VectorXd>(errors.data(), Eigen::Index(errors.size()))));
}

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
