#pragma once
// The sparse sign embedding the sketch solver (sketch.h) mixes a system's rows with: a random
// linear map to a few times fewer rows that keeps the norms of a column space's vectors within a
// bounded distortion (a subspace embedding), at a few additions per input entry.

#include <cstdint>
#include <vector>

#include "nn/sampled/blas.h"

namespace hnn::nn::sampled {

/// Nonzeros per input row of the sparse sign embedding (8: Tropp et al.'s robust choice; a
/// CountSketch's 1 needs many more rows for the same distortion).
inline constexpr int kSketchNonzeros = 8;

/// A sparse sign embedding S (rows_out x rows_in): each input row is added to kSketchNonzeros
/// distinct output rows with random signs and weight 1/sqrt(kSketchNonzeros), so that
/// E |S x|² = |x|².
class SparseSign {
 public:
  SparseSign(Eigen::Index rows_in, Eigen::Index rows_out, std::uint64_t seed);
  Eigen::Index rows_in() const { return rows_in_; }
  Eigen::Index rows_out() const { return rows_out_; }
  /// S x (rows_out x x.cols()), column by column on the engine's threads: the same bits at any
  /// thread count.
  ColMat apply(const ColMat& x) const;

 private:
  Eigen::Index rows_in_, rows_out_;
  int per_row_;
  std::vector<std::int32_t> targets_;  // per_row_ output rows for each input row
  std::vector<double> weights_;        // their signed weights
};

}  // namespace hnn::nn::sampled
