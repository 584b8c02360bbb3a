#include "nn/sampled/sparse_sign.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "autodiff/parallel.h"

namespace hnn::nn::sampled {

using Eigen::Index;

SparseSign::SparseSign(Index rows_in, Index rows_out, std::uint64_t seed)
    : rows_in_(rows_in),
      rows_out_(rows_out),
      per_row_(int(std::min<Index>(kSketchNonzeros, rows_out))),
      targets_(std::size_t(rows_in * per_row_)),
      weights_(targets_.size()) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::int32_t> row(0, std::int32_t(rows_out - 1));
  const double weight = 1 / std::sqrt(double(per_row_));
  for (std::size_t i = 0; i < std::size_t(rows_in); ++i) {
    std::int32_t* chosen = targets_.data() + i * std::size_t(per_row_);
    for (int k = 0; k < per_row_; ++k) {
      do chosen[k] = row(rng);
      while (std::find(chosen, chosen + k, chosen[k]) != chosen + k);
      weights_[i * std::size_t(per_row_) + std::size_t(k)] = (rng() & 1) ? weight : -weight;
    }
  }
}

ColMat SparseSign::apply(const ColMat& x) const {
  ColMat out = ColMat::Zero(rows_out_, x.cols());
  const int parts = int(std::min<Index>(x.cols(), ad::num_threads()));
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock cols = ad::row_block(x.cols(), parts, part);
    for (Index j = cols.begin; j < cols.end; ++j) {
      const double* in = x.col(j).data();
      double* to = out.col(j).data();
      const std::int32_t* target = targets_.data();
      const double* weight = weights_.data();
      for (Index i = 0; i < rows_in_; ++i) {
        for (int k = 0; k < per_row_; ++k) to[*target++] += *weight++ * in[i];
      }
    }
  });
  return out;
}

}  // namespace hnn::nn::sampled
