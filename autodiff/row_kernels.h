#pragma once
// Internal: reductions and broadcasts along the rows of row-major matrices, written row by row
// so that they vectorise. Eigen's colwise().sum() and replicate() walk a row-major matrix down
// its columns (a strided scalar loop, and an integer division per element for replicate), which
// cost as much as a GEMM of the MLP kernels.

#include <Eigen/Core>

namespace hnn::ad::detail {

/// out (1 x cols) = the sum of x's rows.
template <typename X, typename Out>
void column_sums(const X& x, Out&& out) {
  if (x.rows() == 0) {
    out.setZero();
    return;
  }
  out = x.row(0);
  for (Eigen::Index i = 1; i < x.rows(); ++i) out += x.row(i);
}

/// Every row of out = row (1 x cols).
template <typename Out, typename Row>
void fill_rows(Out&& out, const Row& row) {
  for (Eigen::Index i = 0; i < out.rows(); ++i) out.row(i) = row;
}

}  // namespace hnn::ad::detail
