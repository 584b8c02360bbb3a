#include "tasks/train/rollout_objective.h"

#include <algorithm>

#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/loss.h"
#include "tasks/data/dataset.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// Curves evaluate at most this many windows of each split.
constexpr Eigen::Index kCurveWindows = 2000;

template <typename T>
ad::Var<T> constant_rows(const Batch& m, const std::vector<Eigen::Index>* rows) {
  if (rows == nullptr) return ad::Var<T>::constant(m.cast<T>());
  ad::Matrix<T> out(Eigen::Index(rows->size()), m.cols());
  for (std::size_t i = 0; i < rows->size(); ++i)
    out.row(Eigen::Index(i)) = m.row((*rows)[i]).cast<T>();
  return ad::Var<T>::constant(out);
}

}  // namespace

RolloutWindows rollout_windows(const std::vector<Stretch>& stretches, int horizon) {
  HNN_TASKS_CHECK(horizon >= 1, "the rollout horizon must be at least 1 step, got {}", horizon);
  Eigen::Index count = 0, longest = 0, dim = 0;
  for (const Stretch& s : stretches) {
    count += std::max<Eigen::Index>(0, s.x.rows() - horizon);
    longest = std::max(longest, s.x.rows());
    dim = s.x.cols();
  }
  HNN_TASKS_CHECK(count > 0,
                  "a horizon of {} steps is past the end of every training stretch (the longest "
                  "has {} points, so {} steps at most)",
                  horizon, longest, std::max<Eigen::Index>(0, longest - 1));
  RolloutWindows w;
  w.start.resize(count, dim);
  w.next.assign(std::size_t(horizon), Batch(count, dim));
  w.step.assign(std::size_t(horizon), Batch(count, 1));
  Eigen::Index row = 0;
  for (const Stretch& s : stretches) {
    for (Eigen::Index i = 0; i + horizon < s.x.rows(); ++i, ++row) {
      w.start.row(row) = s.x.row(i);
      for (int j = 0; j < horizon; ++j) {
        w.next[std::size_t(j)].row(row) = s.x.row(i + j + 1);
        w.step[std::size_t(j)](row, 0) = s.t(i + j + 1) - s.t(i + j);
      }
    }
  }
  return w;
}

template <typename T>
RolloutObjective<T>::RolloutObjective(nn::DynamicsModel<T>& model, RolloutWindows train,
                                      RolloutWindows test, Eigen::Index batch_size,
                                      const nn::AdamOptions& adam, std::uint64_t seed)
    : model_(model),
      train_(std::move(train)),
      test_(std::move(test)),
      adam_(adam),
      sampler_(train_.count(), batch_size, RowSampler::Draw::kWithReplacement, seed) {}

// One RK4 step per sampling interval, each row with its own step length.
template <typename T>
ad::Var<T> RolloutObjective<T>::loss(const RolloutWindows& w,
                                     const std::vector<Eigen::Index>* rows) const {
  ad::Var<T> x = constant_rows<T>(w.start, rows);
  ad::Var<T> total;
  for (std::size_t j = 0; j < w.next.size(); ++j) {
    const ad::Var<T> h = constant_rows<T>(w.step[j], rows);
    const ad::Var<T> half = h * T(0.5);
    const ad::Var<T> k1 = model_.time_derivative(x);
    const ad::Var<T> k2 = model_.time_derivative(x + half * k1);
    const ad::Var<T> k3 = model_.time_derivative(x + half * k2);
    const ad::Var<T> k4 = model_.time_derivative(x + h * k3);
    x = x + (h * T(1.0 / 6.0)) * (k1 + T(2) * k2 + T(2) * k3 + k4);
    const ad::Var<T> step_loss = nn::mse(x, constant_rows<T>(w.next[j], rows));
    total = total.defined() ? total + step_loss : step_loss;
  }
  return total * T(1.0 / double(w.next.size()));
}

template <typename T>
ad::Var<T> RolloutObjective<T>::batch_loss() {
  return loss(train_, sampler_.full() ? nullptr : &sampler_.rows());
}

template <typename T>
CurvePoint RolloutObjective<T>::curve_point(long step, double batch_loss) const {
  const auto at_most = [](const RolloutWindows& w) {
    std::vector<Eigen::Index> rows(std::size_t(std::min(kCurveWindows, w.count())));
    for (std::size_t i = 0; i < rows.size(); ++i)
      rows[i] = Eigen::Index(i) * w.count() / Eigen::Index(rows.size());
    return rows;
  };
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const std::vector<Eigen::Index> train_rows = at_most(train_);
  const double train =
      sampler_.full() ? batch_loss : double(loss(train_, &train_rows).value()(0, 0));
  double test = NAN;
  if (test_.count() > 0) {
    const std::vector<Eigen::Index> test_rows = at_most(test_);
    test = double(loss(test_, &test_rows).value()(0, 0));
  }
  return {step, train, test};
}

template <typename T>
std::uint64_t RolloutObjective<T>::data_fingerprint() const {
  return fingerprint(Dataset{train_.start, train_.next.back(), {}, {}});
}

template class RolloutObjective<float>;
template class RolloutObjective<double>;

}  // namespace hnn::tasks
