// batched_spd_solve: one symmetric positive definite solve per row of the batch, by Cholesky (the
// multipliers of constrained mechanics, nn/constrained/). Its backward is written in ops, so it
// differentiates to any order.

#include <algorithm>
#include <cmath>

#include "autodiff/op_builder.h"
#include "autodiff/ops.h"

namespace hnn::ad {

namespace {

// The first row the solve cannot answer, and why.
struct SpdFailure {
  enum Kind { kNone, kNonFiniteBlock, kNonFiniteRhs, kNotPositiveDefinite, kIllConditioned };
  Kind kind = kNone;
  Eigen::Index row = -1;
  double rcond = 0;
};

// Cholesky sym(A) = L L^T of one row-major block, in a scratch n x n buffer (its lower triangle),
// written out rather than taken from Eigen's LLT because that one allocates for its condition
// estimate; the blocks are a few constraints wide, so the loops are short.
template <typename T>
class RowCholesky {
 public:
  explicit RowCholesky(Matrix<T>& scratch) : l_(scratch) {}

  // False when a pivot is not positive (sym(A) is not positive definite).
  bool factor(const T* a, Eigen::Index n) {
    l_.resize(n, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      for (Eigen::Index i = j; i < n; ++i) {
        T s = T(0.5) * (a[i * n + j] + a[j * n + i]);
        for (Eigen::Index k = 0; k < j; ++k) s -= l_(i, k) * l_(j, k);
        if (i == j) {
          if (!(s > T(0))) return false;
          l_(j, j) = std::sqrt(s);
        } else {
          l_(i, j) = s / l_(j, j);
        }
      }
    }
    return true;
  }

  // x = sym(A)^-1 b: L y = b, then L^T x = y (x may alias b).
  void solve(const T* b, T* x) const {
    const Eigen::Index n = l_.rows();
    for (Eigen::Index i = 0; i < n; ++i) {
      T s = b[i];
      for (Eigen::Index k = 0; k < i; ++k) s -= l_(i, k) * x[k];
      x[i] = s / l_(i, i);
    }
    for (Eigen::Index i = n - 1; i >= 0; --i) {
      T s = x[i];
      for (Eigen::Index k = i + 1; k < n; ++k) s -= l_(k, i) * x[k];
      x[i] = s / l_(i, i);
    }
  }

  // 1 / (|sym A|_1 |sym A^-1|_1), the inverse solved column by column into `column` (n x 1).
  double reciprocal_condition(const T* a, Matrix<T>& column) const {
    const Eigen::Index n = l_.rows();
    column.resize(n, 1);
    T norm = 0, inverse_norm = 0;
    for (Eigen::Index c = 0; c < n; ++c) {
      T sum = 0;
      for (Eigen::Index i = 0; i < n; ++i) sum += T(0.5) * std::abs(a[i * n + c] + a[c * n + i]);
      norm = std::max(norm, sum);
      column.setZero();
      column(c, 0) = T(1);
      solve(column.data(), column.data());
      inverse_norm = std::max(inverse_norm, T(column.cwiseAbs().sum()));
    }
    const double rcond = 1.0 / (double(norm) * double(inverse_norm));
    return std::isfinite(rcond) ? rcond : 0;
  }

 private:
  Matrix<T>& l_;
};

// x_r = sym(A_r)^-1 b_r row by row, stopping at the first row that cannot be solved. The scratch
// buffers are the node's (kept across recycling: a warmed-up step allocates nothing).
template <typename T>
SpdFailure solve_spd_rows(const Matrix<T>& a, const Matrix<T>& b, Node<T>& node) {
  const Eigen::Index n = b.cols();
  node.buffers.resize(2);
  RowCholesky<T> cholesky(node.buffers[0]);
  node.value.resize(b.rows(), n);
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    if (!a.row(r).allFinite()) return {SpdFailure::kNonFiniteBlock, r};
    if (!b.row(r).allFinite()) return {SpdFailure::kNonFiniteRhs, r};
    if (!cholesky.factor(a.row(r).data(), n)) return {SpdFailure::kNotPositiveDefinite, r};
    const double rcond = cholesky.reciprocal_condition(a.row(r).data(), node.buffers[1]);
    if (!(rcond >= double(kBatchedSolveMinRcond<T>))) {
      return {SpdFailure::kIllConditioned, r, rcond};
    }
    cholesky.solve(b.row(r).data(), node.value.row(r).data());
  }
  return {};
}

template <typename T>
void throw_spd_failure(const SpdFailure& bad, Eigen::Index rows) {
  switch (bad.kind) {
    case SpdFailure::kNone:
      return;
    case SpdFailure::kNonFiniteBlock:
      throw Error(
          fmt::format("batched_spd_solve: block {} of {} has a non-finite entry", bad.row, rows));
    case SpdFailure::kNonFiniteRhs:
      throw Error(fmt::format("batched_spd_solve: right-hand side {} of {} has a non-finite entry",
                              bad.row, rows));
    case SpdFailure::kNotPositiveDefinite:
      throw Error(fmt::format(
          "batched_spd_solve: block {} of {} is not positive definite (redundant or degenerate "
          "constraints give a singular Gram block)",
          bad.row, rows));
    case SpdFailure::kIllConditioned:
      throw Error(fmt::format(
          "batched_spd_solve: block {} of {} is ill-conditioned (rcond {:.3g}, below the minimum "
          "{:.3g} for this precision)",
          bad.row, rows, bad.rcond, double(kBatchedSolveMinRcond<T>)));
  }
}

// S x = b with S = sym(A): gb = S^-1 g, and <g, dx> = -<gb, sym(dA) x> = -<sym(gb x^T), dA>.
template <typename T>
void spd_solve_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>& a = n.inputs[0];
  const Var<T> gb = batched_spd_solve(a, g);
  if (s.wants(0)) {
    const Var<T> x = Var<T>::of(n);
    s.add(0, (batched_outer(gb, x) + batched_outer(x, gb)) * T(-0.5));
  }
  if (s.wants(1)) s.add(1, gb);
}

}  // namespace

template <typename T>
Var<T> batched_spd_solve(const Var<T>& a, const Var<T>& b) {
  const Eigen::Index n = b.cols();
  HNN_AD_CHECK(a.rows() == b.rows() && n > 0 && a.cols() == n * n,
               "batched_spd_solve: blocks {} do not match right-hand sides {} (expected {}: one "
               "{}x{} block per row)",
               a.shape(), b.shape(), shape_str(b.rows(), n * n), n, n);
  Node<T>& node = detail::record<T>("batched_spd_solve", {a, b}, spd_solve_backward<T>);
  throw_spd_failure<T>(solve_spd_rows<T>(a.value(), b.value(), node), a.rows());
  return Var<T>::of(node);
}

template Var<float> batched_spd_solve(const Var<float>&, const Var<float>&);
template Var<double> batched_spd_solve(const Var<double>&, const Var<double>&);

}  // namespace hnn::ad
