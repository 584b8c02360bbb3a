// The peer's relative-error metric and its floor (metric.h).
#include "physics/constrained/metric.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace hnn::physics::constrained {

Eigen::VectorXd relative_errors(const Batch& predicted, const Batch& truth) {
  if (predicted.rows() != truth.rows() || predicted.cols() != truth.cols())
    throw std::invalid_argument(fmt::format("relative_errors: predicted is {}x{}, truth {}x{}",
                                            predicted.rows(), predicted.cols(), truth.rows(),
                                            truth.cols()));
  return (predicted - truth).rowwise().norm().array() /
         (predicted.rowwise().norm() + truth.rowwise().norm()).array();
}

double trajectory_geometric_mean(const Eigen::VectorXd& errors, double dt, double horizon) {
  if (errors.size() < 2 || !(dt > 0.0) || !(horizon > 0.0))
    throw std::invalid_argument("trajectory_geometric_mean: needs 2+ errors, dt > 0, horizon > 0");
  const Eigen::ArrayXd logs = (errors.array() + 1e-8).log();
  const double trapezoid = logs.sum() - 0.5 * (logs[0] + logs[logs.size() - 1]);
  return std::exp(dt * trapezoid / horizon);
}

double pooled_geometric_mean(const Eigen::VectorXd& values) {
  if (values.size() == 0) throw std::invalid_argument("pooled_geometric_mean: no values");
  return std::exp(values.array().log().mean());
}

RolloutScore score_rollouts(const std::vector<Batch>& predicted, const std::vector<Batch>& truth,
                            double dt, double horizon) {
  if (predicted.size() != truth.size() || truth.empty())
    throw std::invalid_argument(
        fmt::format("score_rollouts: {} predicted times, {} true", predicted.size(), truth.size()));
  const Eigen::Index rows = truth.front().rows();
  const auto times = static_cast<Eigen::Index>(truth.size());
  Eigen::MatrixXd errors(rows, times);
  for (Eigen::Index k = 0; k < times; ++k) errors.col(k) = relative_errors(predicted[k], truth[k]);
  RolloutScore score;
  score.per_trajectory.resize(rows);
  std::vector<double> kept;
  for (Eigen::Index r = 0; r < rows; ++r) {
    if (!errors.row(r).allFinite()) {
      score.per_trajectory[r] = std::nan("");
      ++score.failed;
      continue;
    }
    score.per_trajectory[r] = trajectory_geometric_mean(errors.row(r).transpose(), dt, horizon);
    kept.push_back(score.per_trajectory[r]);
  }
  score.geometric_mean =
      kept.empty() ? std::nan("")
                   : pooled_geometric_mean(Eigen::Map<Eigen::VectorXd>(kept.data(), kept.size()));
  return score;
}

FloorResult floor_score(const ConstrainedSystem& system, const Batch& z0,
                        const std::vector<Batch>& truth, std::mt19937_64& rng,
                        const TruthOptions& options, double eps, FloorProjection projection) {
  const std::vector<double> times = system.output_times();
  if (truth.size() != times.size() || truth.front().rows() != z0.rows())
    throw std::invalid_argument(fmt::format(
        "floor_score: the truth must hold the {} output times of '{}', one row per start",
        times.size(), system.name()));
  std::normal_distribution<double> normal;
  Batch moved = z0;
  for (Eigen::Index i = 0; i < moved.size(); ++i) moved.data()[i] += eps * normal(rng);
  const Batch start =
      projection == FloorProjection::kPeer ? system.project_peer(moved) : system.project(moved);
  FloorResult result;
  result.perturbed = simulate_constrained(system, start, times, options).states;
  result.score = score_rollouts(result.perturbed, truth, system.spec().dt, system.spec().horizon);
  return result;
}

}  // namespace hnn::physics::constrained
