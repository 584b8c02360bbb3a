#include "tasks/train/field_objective.h"

#include <cmath>

#include "nn/loss.h"

namespace hnn::tasks {

namespace {

// Loss curves evaluate at most this many rows of each split: enough for a smooth curve,
// cheap enough to record 100 points on the largest datasets.
constexpr Eigen::Index kCurveRows = 4000;
constexpr Eigen::Index kEvalChunk = 4096;

}  // namespace

template <typename T>
FieldObjective<T>::FieldObjective(nn::DynamicsModel<T>& model, const Dataset& data,
                                  Eigen::Index batch_size, const nn::AdamOptions& adam,
                                  std::uint64_t seed)
    : model_(model),
      data_(data),
      adam_(adam),
      sampler_(data.train_x.rows(), batch_size, RowSampler::Draw::kWithReplacement, seed),
      x_(data.train_x.cast<T>()),
      dxdt_(data.train_dxdt.cast<T>()) {
  if (!sampler_.full()) {
    batch_x_.resize(batch_size, x_.cols());
    batch_dxdt_.resize(batch_size, x_.cols());
  }
}

template <typename T>
ad::Var<T> FieldObjective<T>::batch_loss() {
  return rows_loss(model_, {0, gather_batch()});
}

template <typename T>
Eigen::Index FieldObjective<T>::gather_batch() {
  if (sampler_.full()) return x_.rows();
  const std::vector<Eigen::Index>& rows = sampler_.rows();  // into buffers sized once
  for (std::size_t i = 0; i < rows.size(); ++i) {
    batch_x_.row(Eigen::Index(i)) = x_.row(rows[i]);
    batch_dxdt_.row(Eigen::Index(i)) = dxdt_.row(rows[i]);
  }
  return batch_x_.rows();
}

template <typename T>
ad::Var<T> FieldObjective<T>::rows_loss(const nn::DynamicsModel<T>& model,
                                        ad::RowBlock block) const {
  const bool full = sampler_.full();
  const auto rows = [&](const ad::Matrix<T>& m) {
    return ad::Var<T>::constant(m.middleRows(block.begin, block.size()));
  };
  return nn::mse(model.time_derivative(rows(full ? x_ : batch_x_)),
                 rows(full ? dxdt_ : batch_dxdt_));
}

template <typename T>
CurvePoint FieldObjective<T>::curve_point(long step, double batch_loss) const {
  const Eigen::Index train = std::min(kCurveRows, data_.train_x.rows());
  const Eigen::Index test = std::min(kCurveRows, data_.test_x.rows());
  return {step,
          sampler_.full()
              ? batch_loss
              : field_mse(model_, data_.train_x.topRows(train), data_.train_dxdt.topRows(train)),
          test > 0 ? field_mse(model_, data_.test_x.topRows(test), data_.test_dxdt.topRows(test))
                   : NAN};
}

template <typename T>
double field_mse(const nn::DynamicsModel<T>& model, const Batch& x, const Batch& dxdt) {
  double total = 0;
  for (Eigen::Index start = 0; start < x.rows(); start += kEvalChunk) {
    const Eigen::Index n = std::min(kEvalChunk, x.rows() - start);
    const ad::Matrix<T> pred = model.field(x.middleRows(start, n).cast<T>());
    total += (pred.template cast<double>() - dxdt.middleRows(start, n)).squaredNorm();
  }
  return total / double(x.size());
}

template class FieldObjective<float>;
template class FieldObjective<double>;
template double field_mse(const nn::DynamicsModel<float>&, const Batch&, const Batch&);
template double field_mse(const nn::DynamicsModel<double>&, const Batch&, const Batch&);

}  // namespace hnn::tasks
