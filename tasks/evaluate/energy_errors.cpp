#include "tasks/evaluate/energy_errors.h"

#include <algorithm>
#include <cmath>

namespace hnn::tasks {

namespace {

// The energy MSE's standard error: the reference's interleaved splits.
constexpr int kSplits = 5;

}  // namespace

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

nn::MeanStderr relative_energy_mse(const Rollouts& r) {
  nn::MeanStderr out = energy_mse(r);
  double sum = 0;
  Eigen::Index points = 0;
  for (std::size_t i = 0; i < r.failed.size(); ++i) {
    if (r.failed[i]) continue;
    sum += r.true_energy.row(Eigen::Index(i)).squaredNorm();
    points += r.true_energy.cols();
  }
  const double mean_square = points > 0 ? sum / double(points) : NAN;
  out.mean = mean_square > 0 ? out.mean / mean_square : NAN;
  out.std_error = mean_square > 0 ? out.std_error / mean_square : NAN;
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

}  // namespace hnn::tasks
