#include "tasks/evaluate/loss_stats.h"

#include <cmath>
#include <stdexcept>

#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

namespace {

// Rows of a split evaluated at once: the engine keeps several rows x width buffers per chunk,
// which at 4096 rows of a width-3000 layer (98 MB each) were mapped and zeroed afresh every
// chunk. `hnn evaluate` of a double-pendulum run at width 3000 (40k points) took 1.36 s at 512
// rows, 0.98 s at 128 and 1.03 s at 32 (one engine thread below 64 rows a part; Zen 3,
// farm-bench medians of 5).
constexpr Eigen::Index kChunk = 128;

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

}  // namespace hnn::tasks
