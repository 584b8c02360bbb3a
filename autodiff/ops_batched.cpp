// Batched small linear algebra: one small matrix per row of the batch, flattened row-major in
// that row (the per-sample Hessian blocks of a Lagrangian network). Each backward is written in
// these three ops, so they differentiate to any order.

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <utility>

#include "autodiff/op_builder.h"
#include "autodiff/ops.h"

namespace hnn::ad {

namespace {

template <typename T>
using RowMajorMap =
    Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

// ---- batched_solve -----------------------------------------------------------------------------

// The first row batched_solve cannot answer, and why.
struct BadRow {
  enum Kind { kNone, kNonFiniteBlock, kNonFiniteRhs, kIllConditioned };
  Kind kind = kNone;
  Eigen::Index row = -1;
  double rcond = 0;
};

// 1 / (|A|_1 |A^-1|_1) by Eigen's estimate from the factors; 0 for an exactly singular block,
// whose estimate would be computed from infinities (and could come out NaN).
template <typename Lu>
double reciprocal_condition(const Lu& lu) {
  if ((lu.matrixLU().diagonal().array() == 0).any()) return 0;
  const double rcond = double(lu.rcond());
  return std::isfinite(rcond) ? rcond : 0;
}

// Partial-pivot LU of one N x N block (N <= 4), unrolled by the compiler, with the exact
// 1-norm condition from the inverse: 2 to 7 times faster than Eigen's fixed-size PartialPivLU
// with its rcond estimate (measured at R = 512: 7x at N = 2, 3x at 3, 2x at 4), allocation-free.
template <typename T, int N>
class SmallLu {
 public:
  // Factors the row-major block a; false when a pivot is exactly zero (singular).
  bool factor(const T* a) {
    norm1_ = 0;
    for (int j = 0; j < N; ++j) {
      T column = 0;
      for (int i = 0; i < N; ++i) column += std::abs(a[i * N + j]);
      norm1_ = std::max(norm1_, column);
    }
    for (int i = 0; i < N; ++i) {
      perm_[i] = i;
      for (int j = 0; j < N; ++j) lu_[i][j] = a[i * N + j];
    }
    for (int k = 0; k < N; ++k) {
      int pivot = k;
      for (int i = k + 1; i < N; ++i)
        if (std::abs(lu_[i][k]) > std::abs(lu_[pivot][k])) pivot = i;
      if (lu_[pivot][k] == T(0)) return false;
      if (pivot != k) {
        std::swap(lu_[k], lu_[pivot]);
        std::swap(perm_[k], perm_[pivot]);
      }
      const T inverse = T(1) / lu_[k][k];
      for (int i = k + 1; i < N; ++i) {
        const T l = lu_[i][k] * inverse;
        lu_[i][k] = l;
        for (int j = k + 1; j < N; ++j) lu_[i][j] -= l * lu_[k][j];
      }
    }
    return true;
  }

  // 1 / (|A|_1 |A^-1|_1), with A^-1 = U^-1 L^-1 P formed row by row (all N columns at once).
  double reciprocal_condition() const {
    T inv[N][N];
    for (int i = 0; i < N; ++i) {
      for (int c = 0; c < N; ++c) inv[i][c] = perm_[i] == c ? T(1) : T(0);
      for (int j = 0; j < i; ++j)
        for (int c = 0; c < N; ++c) inv[i][c] -= lu_[i][j] * inv[j][c];
    }
    for (int i = N - 1; i >= 0; --i) {
      for (int j = i + 1; j < N; ++j)
        for (int c = 0; c < N; ++c) inv[i][c] -= lu_[i][j] * inv[j][c];
      for (int c = 0; c < N; ++c) inv[i][c] /= lu_[i][i];
    }
    T inverse_norm1 = 0;
    for (int c = 0; c < N; ++c) {
      T column = 0;
      for (int i = 0; i < N; ++i) column += std::abs(inv[i][c]);
      inverse_norm1 = std::max(inverse_norm1, column);
    }
    const double rcond = 1.0 / (double(norm1_) * double(inverse_norm1));
    return std::isfinite(rcond) ? rcond : 0;
  }

  // x = A^-1 b, or A^-T b: P A = L U, so A^T = U^T L^T P and A^-T b = P^T L^-T U^-T b.
  void solve(const T* b, T* x, bool transpose) const {
    T y[N];
    if (!transpose) {
      for (int i = 0; i < N; ++i) {
        y[i] = b[perm_[i]];
        for (int j = 0; j < i; ++j) y[i] -= lu_[i][j] * y[j];
      }
      for (int i = N - 1; i >= 0; --i) {
        for (int j = i + 1; j < N; ++j) y[i] -= lu_[i][j] * y[j];
        y[i] /= lu_[i][i];
      }
      for (int i = 0; i < N; ++i) x[i] = y[i];
      return;
    }
    for (int i = 0; i < N; ++i) {  // U^T y = b
      y[i] = b[i];
      for (int j = 0; j < i; ++j) y[i] -= lu_[j][i] * y[j];
      y[i] /= lu_[i][i];
    }
    for (int i = N - 1; i >= 0; --i)  // L^T z = y
      for (int j = i + 1; j < N; ++j) y[i] -= lu_[j][i] * y[j];
    for (int i = 0; i < N; ++i) x[perm_[i]] = y[i];  // x = P^T z
  }

 private:
  T lu_[N][N];
  int perm_[N];
  T norm1_;
};

// x_r = op(A_r)^-1 b_r row by row with SmallLu, stopping at the first row that cannot be solved.
template <typename T, int N>
BadRow solve_small_rows(const Matrix<T>& a, const Matrix<T>& b, bool transpose, Matrix<T>& x) {
  SmallLu<T, N> lu;
  x.resize(b.rows(), N);
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    if (!a.row(r).allFinite()) return {BadRow::kNonFiniteBlock, r};
    if (!b.row(r).allFinite()) return {BadRow::kNonFiniteRhs, r};
    const double rcond = lu.factor(a.row(r).data()) ? lu.reciprocal_condition() : 0.0;
    if (!(rcond >= double(kBatchedSolveMinRcond<T>))) return {BadRow::kIllConditioned, r, rcond};
    lu.solve(b.row(r).data(), x.row(r).data(), transpose);
  }
  return {};
}

// The same for blocks above 4x4, with Eigen's PartialPivLU and its rcond estimate (this path
// allocates: the Lagrangian networks it serves have few coordinates).
template <typename T>
BadRow solve_large_rows(const Matrix<T>& a, const Matrix<T>& b, bool transpose, Matrix<T>& x) {
  using Block = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using Vector = Eigen::Matrix<T, Eigen::Dynamic, 1>;
  const Eigen::Index n = b.cols();
  Eigen::PartialPivLU<Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>> lu(n);
  x.resize(b.rows(), n);
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const Eigen::Map<const Block> block(a.row(r).data(), n, n);
    const Eigen::Map<const Vector> rhs(b.row(r).data(), n);
    if (!block.allFinite()) return {BadRow::kNonFiniteBlock, r};
    if (!rhs.allFinite()) return {BadRow::kNonFiniteRhs, r};
    lu.compute(block);
    const double rcond = reciprocal_condition(lu);
    if (!(rcond >= double(kBatchedSolveMinRcond<T>))) return {BadRow::kIllConditioned, r, rcond};
    Eigen::Map<Vector> out(x.row(r).data(), n);
    if (transpose)
      out = lu.transpose().solve(rhs);
    else
      out = lu.solve(rhs);
  }
  return {};
}

template <typename T>
BadRow solve_any_size(const Matrix<T>& a, const Matrix<T>& b, bool transpose, Matrix<T>& x) {
  switch (b.cols()) {
    case 1:
      return solve_small_rows<T, 1>(a, b, transpose, x);
    case 2:
      return solve_small_rows<T, 2>(a, b, transpose, x);
    case 3:
      return solve_small_rows<T, 3>(a, b, transpose, x);
    case 4:
      return solve_small_rows<T, 4>(a, b, transpose, x);
    default:
      return solve_large_rows<T>(a, b, transpose, x);
  }
}

template <typename T>
void throw_bad_row(const BadRow& bad, Eigen::Index rows) {
  switch (bad.kind) {
    case BadRow::kNone:
      return;
    case BadRow::kNonFiniteBlock:
      throw Error(
          fmt::format("batched_solve: block {} of {} has a non-finite entry", bad.row, rows));
    case BadRow::kNonFiniteRhs:
      throw Error(fmt::format("batched_solve: right-hand side {} of {} has a non-finite entry",
                              bad.row, rows));
    case BadRow::kIllConditioned:
      throw Error(fmt::format(
          "batched_solve: block {} of {} is singular or ill-conditioned (rcond {:.3g}, below the "
          "minimum {:.3g} for this precision)",
          bad.row, rows, bad.rcond, double(kBatchedSolveMinRcond<T>)));
  }
}

// A x = b: gb = A^-T g, gA = -gb x^T. A^T x = b: gb = A^-1 g, gA = -(gb x^T)^T = -x gb^T.
template <typename T>
void solve_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>& a = n.inputs[0];
  const bool transpose = n.saved[0] != 0;
  const Var<T> gb = batched_solve(a, g, !transpose);
  const Var<T> x = Var<T>::of(n);
  if (s.wants(0)) s.add(0, neg(transpose ? batched_outer(x, gb) : batched_outer(gb, x)));
  if (s.wants(1)) s.add(1, gb);
}

// ---- batched_matvec and batched_outer
// ------------------------------------------------------------

// y_r = op(A_r) v_r, with A_r k x n (or n x k, transposed) and n = v.cols(). Plain loops: the
// blocks are a few constraints wide, where a per-row Eigen product spent its time dispatching.
template <typename T>
void matvec_rows(const Matrix<T>& a, const Matrix<T>& v, bool transpose, Matrix<T>& y) {
  const Eigen::Index n = v.cols(), k = a.cols() / n;
  y.resize(a.rows(), k);
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const T* block = a.row(r).data();
    const T* vr = v.row(r).data();
    T* yr = y.row(r).data();
    for (Eigen::Index i = 0; i < k; ++i) {
      T sum = 0;
      for (Eigen::Index j = 0; j < n; ++j)
        sum += (transpose ? block[j * k + i] : block[i * n + j]) * vr[j];
      yr[i] = sum;
    }
  }
}

// y = A v: gA = g v^T, gv = A^T g. y = A^T v: gA = v g^T, gv = A g.
template <typename T>
void matvec_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&a = n.inputs[0], &v = n.inputs[1];
  const bool transpose = n.saved[0] != 0;
  if (s.wants(0)) s.add(0, transpose ? batched_outer(v, g) : batched_outer(g, v));
  if (s.wants(1)) s.add(1, batched_matvec(a, g, !transpose));
}

// Y = u v^T (n x m): gu = G v, gv = G^T u.
template <typename T>
void outer_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&u = n.inputs[0], &v = n.inputs[1];
  if (s.wants(0)) s.add(0, batched_matvec(g, v, false));
  if (s.wants(1)) s.add(1, batched_matvec(g, u, true));
}

}  // namespace

template <typename T>
Var<T> batched_solve(const Var<T>& a, const Var<T>& b, bool transpose_a) {
  const Eigen::Index n = b.cols();
  HNN_AD_CHECK(a.rows() == b.rows() && n > 0 && a.cols() == n * n,
               "batched_solve: blocks {} do not match right-hand sides {} (expected {}: one {}x{} "
               "block per row)",
               a.shape(), b.shape(), shape_str(b.rows(), n * n), n, n);
  Node<T>& node = detail::record<T>("batched_solve", {a, b}, solve_backward<T>);
  node.saved[0] = double(transpose_a);
  throw_bad_row<T>(solve_any_size<T>(a.value(), b.value(), transpose_a, node.value), a.rows());
  return Var<T>::of(node);
}

template <typename T>
Var<T> batched_matvec(const Var<T>& a, const Var<T>& v, bool transpose_a) {
  const Eigen::Index n = v.cols();
  HNN_AD_CHECK(a.rows() == v.rows() && n > 0 && a.cols() % n == 0,
               "batched_matvec: blocks {} do not match vectors {} (expected {} rows of k*{} "
               "entries, k x {} blocks{})",
               a.shape(), v.shape(), v.rows(), n, n, transpose_a ? " used transposed" : "");
  Node<T>& node = detail::record<T>("batched_matvec", {a, v}, matvec_backward<T>);
  node.saved[0] = double(transpose_a);
  matvec_rows<T>(a.value(), v.value(), transpose_a, node.value);
  return Var<T>::of(node);
}

template <typename T>
Var<T> batched_outer(const Var<T>& u, const Var<T>& v) {
  HNN_AD_CHECK(u.rows() == v.rows(), "batched_outer: row counts differ: {} and {}", u.shape(),
               v.shape());
  Node<T>& node = detail::record<T>("batched_outer", {u, v}, outer_backward<T>);
  const Eigen::Index n = u.cols(), m = v.cols();
  node.value.resize(u.rows(), n * m);
  for (Eigen::Index r = 0; r < u.rows(); ++r) {
    const T* ur = u.value().row(r).data();
    const T* vr = v.value().row(r).data();
    T* out = node.value.row(r).data();
    for (Eigen::Index i = 0; i < n; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) out[i * m + j] = ur[i] * vr[j];
    }
  }
  return Var<T>::of(node);
}

#define HNN_INSTANTIATE(T)                                            \
  template Var<T> batched_solve(const Var<T>&, const Var<T>&, bool);  \
  template Var<T> batched_matvec(const Var<T>&, const Var<T>&, bool); \
  template Var<T> batched_outer(const Var<T>&, const Var<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
