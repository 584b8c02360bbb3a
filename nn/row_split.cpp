#include "nn/row_split.h"

#include <algorithm>

#include "autodiff/grad.h"
#include "autodiff/row_kernels.h"
#include "nn/hnn.h"

namespace hnn::nn {

// Note [Rows, not ops]
// A training step of the peers' sizes is a few thousand ops (a 2-chain CHNN step 1,982), most of
// them small: the mechanics' 2 x 2 solves, slices, the integrator's stage sums. Split op by op,
// every GEMM and large elementwise pass is a parallel region, and the small ops run on the
// calling thread while the worker waits (17% of the worker's time in a CHNN step). Split by rows,
// each thread runs the whole step on its block of the batch, small ops included, and the threads
// meet once, to sum the gradients. The products keep their shapes (each thread multiplied its
// half of the rows before too), so the GEMMs lose nothing. Each part differentiates through its
// own replica of the model: a sweep writes its bookkeeping into the leaves it reaches
// (autodiff/grad.cpp), so two threads must not sweep through the same leaves.

int row_split_parts(Index rows, int threads) {
  return int(std::clamp<Index>(rows / kMinSplitRows, 1, std::max(threads, 1)));
}

template <typename T>
RowSplit<T>::RowSplit(const DynamicsModel<T>& model, int parts)
    : model_(model),
      parts_(std::max(parts, 1)),
      params_(std::size_t(parts_)),
      part_grads_(std::size_t(parts_)),
      weighed_(std::size_t(parts_)),
      losses_(std::size_t(parts_)) {
  params_[0] = model.parameters();
  for (const ad::Var<T>& w : params_[0]) sums_.push_back(ad::Var<T>::leaf(w.value(), false));
  for (int p = 1; p < parts_; ++p) {
    replicas_.push_back(cast_model<T>(model));
    params_[std::size_t(p)] = replicas_.back()->parameters();
    for (const ad::Var<T>& w : params_[0]) weighed_[std::size_t(p)].push_back(w.value());
  }
}

template <typename T>
void RowSplit<T>::sync(int p) {
  if (p == 0) return;
  std::vector<ad::Var<T>>& mine = params_[std::size_t(p)];
  for (std::size_t i = 0; i < mine.size(); ++i) mine[i].mutable_value() = params_[0][i].value();
}

template <typename T>
void RowSplit<T>::keep(int p, Index rows, Index total, const ad::Var<T>& loss) {
  const double weight = double(rows) / double(total);
  losses_[std::size_t(p)] = weight * double(loss.item());
  std::vector<ad::Var<T>>& grads = part_grads_[std::size_t(p)];
  ad::grad_into(loss, params_[std::size_t(p)], grads);
  for (std::size_t i = 0; i < grads.size(); ++i) {
    // Part 0 writes into the sums themselves, the others into their own buffers.
    Matrix<T>& out = p == 0 ? sums_[i].mutable_value() : weighed_[std::size_t(p)][i];
    out = T(weight) * grads[i].value();
  }
}

template <typename T>
double RowSplit<T>::sum_into(std::vector<ad::Var<T>>& grads) {
  double loss = 0;
  for (double l : losses_) loss += l;
  // Every thread adds its element block of every parameter: one parallel region for them all.
  ad::parallel_for(parts_, [&](int t) {
    for (std::size_t i = 0; i < sums_.size(); ++i) {
      Matrix<T>& sum = sums_[i].mutable_value();
      const ad::RowBlock e = ad::element_block(sum.size(), parts_, t);
      for (int p = 1; p < parts_; ++p) {
        ad::detail::flat(sum, e) += ad::detail::flat(weighed_[std::size_t(p)][i], e);
      }
    }
  });
  grads.assign(sums_.begin(), sums_.end());
  return loss;
}

template class RowSplit<float>;
template class RowSplit<double>;

}  // namespace hnn::nn
