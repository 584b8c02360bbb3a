#include "tasks/evaluate/rollouts.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nn/hnn.h"
#include "nn/lnn.h"
#include "physics/integrator.h"
#include "physics/types.h"

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
  const Eigen::Index n = x0.rows(), m = Eigen::Index(r.t.size());
  r.true_energy.setConstant(n, m, NAN);
  r.pred_energy.setConstant(n, m, NAN);
  if (learned.hamiltonian) r.learned_h.setConstant(n, m, NAN);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd path = integrate_one(truth.field(), x0.row(i), r.t, config, nullptr);
    r.truth.push_back(path);
    r.true_energy.row(i) = truth.energy_batch(Batch(path)).transpose();
    try {
      r.pred.push_back(
          integrate_one(learned.field, x0.row(i), r.t, config, &r.nfev, kMaxLearnedSteps));
      r.failed.push_back(false);
      r.pred_energy.row(i) = truth.energy_batch(Batch(r.pred.back())).transpose();
      if (learned.hamiltonian)
        r.learned_h.row(i) = learned.hamiltonian(Batch(r.pred.back())).transpose();
    } catch (const physics::IntegrationError& e) {
      r.pred.push_back(Eigen::MatrixXd::Constant(m, x0.cols(), NAN));
      r.failed.push_back(true);
      r.failures.push_back(fmt::format("trajectory {}: {}", i, e.what()));
    }
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

double state_mse(const Rollouts& r) {
  double sum = 0, count = 0;
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    if (r.failed[i]) continue;
    sum += (r.truth[i] - r.pred[i]).squaredNorm();
    count += double(r.truth[i].size());
  }
  return count > 0 ? sum / count : NAN;
}

Eigen::VectorXd relative_state_error(const Eigen::MatrixXd& pred, const Eigen::MatrixXd& truth) {
  return ((pred - truth).rowwise().norm().array() /
          (pred.rowwise().norm() + truth.rowwise().norm()).array())
      .matrix();
}

RelativeError relative_error(const Rollouts& r, double threshold) {
  RelativeError out;
  double log_sum = 0, valid_sum = 0;
  long count = 0, used = 0;
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    if (r.failed[i]) continue;
    const Eigen::MatrixXd& x = r.truth[i];
    const Eigen::MatrixXd& y = r.pred[i];
    double valid = r.t.back() - r.t.front();
    bool passed = false;
    const Eigen::VectorXd error = relative_state_error(y, x);
    for (Eigen::Index k = 1; k < x.rows(); ++k) {
      const double e = error(k);
      log_sum += std::log(std::max(e, 1e-300));
      ++count;
      if (!passed && !(e <= threshold)) {
        valid = r.t[std::size_t(k)] - r.t.front();
        passed = true;
      }
    }
    valid_sum += valid;
    out.censored += passed ? 0 : 1;
    ++used;
  }
  if (count > 0) out.geomean = std::exp(log_sum / double(count));
  if (used > 0) out.valid_time = valid_sum / double(used);
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
