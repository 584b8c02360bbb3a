#pragma once
// Internal: reductions and broadcasts along the rows of row-major matrices, written row by row
// so that they vectorise. Eigen's colwise().sum() and replicate() walk a row-major matrix down
// its columns (a strided scalar loop, and an integer division per element for replicate), which
// cost as much as a GEMM of the MLP kernels.

#include <Eigen/Core>
#include <type_traits>

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

/// out's columns [out_start, out_start + count) = x's columns [start, start + count), both
/// row-major, as plain loops.
/// Eigen assigns a block of a row-major matrix row by row, setting up its inner loop each time:
/// for the one- and two-column slices, pads and joins of the field and integrator steps that
/// cost about 1 us per 128 rows, several times the copy.
template <typename T>
void copy_cols(const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& x,
               Eigen::Index start,
               Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& out,
               Eigen::Index out_start, Eigen::Index count) {
  const Eigen::Index in_stride = x.cols(), out_stride = out.cols();
  const T* in = x.data() + start;
  T* to = out.data() + out_start;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index c = 0; c < count; ++c) to[i * out_stride + c] = in[i * in_stride + c];
  }
}

/// Elements [block.begin, block.end) of m in storage order, as a 1-D array. (Eigen's reshaped()
/// walks a row-major matrix by columns: a strided pass.)
template <typename M, typename Block>
auto flat(M& m, const Block& block) {
  using Array = Eigen::Array<typename M::Scalar, Eigen::Dynamic, 1>;
  using Mapped = std::conditional_t<std::is_const_v<M>, const Array, Array>;
  return Eigen::Map<Mapped>(m.data() + block.begin, block.end - block.begin);
}

/// Every row of out = row (1 x cols).
template <typename Out, typename Row>
void fill_rows(Out&& out, const Row& row) {
  for (Eigen::Index i = 0; i < out.rows(); ++i) out.row(i) = row;
}

}  // namespace hnn::ad::detail
