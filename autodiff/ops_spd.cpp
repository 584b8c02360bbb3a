// batched_spd_solve: one symmetric positive definite solve per row of the batch, by Cholesky (the
// multipliers of constrained mechanics, nn/constrained/). Its backward is written in ops, so it
// differentiates to any order.

#include <algorithm>
#include <cmath>
#include <vector>

#include "autodiff/op_builder.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"

namespace hnn::ad {

namespace {

// The first row the solve cannot answer, and why.
struct SpdFailure {
  enum Kind { kNone, kNonFiniteBlock, kNonFiniteRhs, kNotPositiveDefinite, kIllConditioned };
  Kind kind = kNone;
  Eigen::Index row = -1;
  double rcond = 0;
};

// Row r's Cholesky factor sym(A_r) = L L^T lives in row r of the node's factors buffer: L
// row-major, its diagonal stored as 1 / L_ii so that the solves multiply. Written out rather
// than taken from Eigen's LLT, which allocates for its condition estimate; the blocks are a few
// constraints wide, so the loops are short and run on raw pointers (per-row Eigen expressions
// spent their time dispatching).
constexpr std::size_t kFactors = 0;

// Per-node state: which matrix the factors belong to, so a later solve can reuse them, and
// where they are: the factoring node's buffer, which a solve that reuses them points at rather
// than copies (every node involved lives on the same tape until it is rewound).
template <typename T>
struct SpdFactors : OpState {
  const Node<T>* matrix = nullptr;
  std::uint32_t generation = 0;
  const Matrix<T>* factors = nullptr;
};

// False when a pivot is not positive (sym(A) is not positive definite).
template <typename T>
bool factor_row(const T* a, Eigen::Index n, T* l) {
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j; i < n; ++i) {
      T s = T(0.5) * (a[i * n + j] + a[j * n + i]);
      for (Eigen::Index k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
      if (i == j) {
        if (!(s > T(0))) return false;
        l[j * n + j] = T(1) / std::sqrt(s);
      } else {
        l[i * n + j] = s * l[j * n + j];
      }
    }
  }
  return true;
}

// x = sym(A)^-1 b from the factor: L y = b, then L^T x = y (x may alias b).
template <typename T>
void solve_row(const T* l, Eigen::Index n, const T* b, T* x) {
  for (Eigen::Index i = 0; i < n; ++i) {
    T s = b[i];
    for (Eigen::Index k = 0; k < i; ++k) s -= l[i * n + k] * x[k];
    x[i] = s * l[i * n + i];
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    T s = x[i];
    for (Eigen::Index k = i + 1; k < n; ++k) s -= l[k * n + i] * x[k];
    x[i] = s * l[i * n + i];
  }
}

// 1 / (|sym A|_1 |sym A^-1|_1), the inverse solved column by column in `column` (n entries).
template <typename T>
double reciprocal_condition(const T* a, const T* l, Eigen::Index n, T* column) {
  T norm = 0, inverse_norm = 0;
  for (Eigen::Index c = 0; c < n; ++c) {
    T sum = 0;
    for (Eigen::Index i = 0; i < n; ++i) sum += T(0.5) * std::abs(a[i * n + c] + a[c * n + i]);
    norm = std::max(norm, sum);
    std::fill_n(column, n, T(0));
    column[c] = T(1);
    solve_row(l, n, column, column);
    T inverse_sum = 0;
    for (Eigen::Index i = 0; i < n; ++i) inverse_sum += std::abs(column[i]);
    inverse_norm = std::max(inverse_norm, inverse_sum);
  }
  const double rcond = 1.0 / (double(norm) * double(inverse_norm));
  return std::isfinite(rcond) ? rcond : 0;
}

// Factors and solves the rows of block r, stopping at the first that cannot be solved; `column`
// is the part's scratch (a node buffer, kept across recycling: a warmed-up step allocates
// nothing).
template <typename T>
SpdFailure factor_and_solve_block(const Matrix<T>& a, const Matrix<T>& b, Node<T>& node, RowBlock r,
                                  Matrix<T>& column, double min_rcond) {
  const Eigen::Index n = b.cols();
  Matrix<T>& factors = node.buffers[kFactors];
  for (Eigen::Index row = r.begin; row < r.end; ++row) {
    if (!a.row(row).allFinite()) return {SpdFailure::kNonFiniteBlock, row};
    if (!b.row(row).allFinite()) return {SpdFailure::kNonFiniteRhs, row};
    T* l = factors.row(row).data();
    if (!factor_row(a.row(row).data(), n, l)) return {SpdFailure::kNotPositiveDefinite, row};
    const double rcond = reciprocal_condition(a.row(row).data(), l, n, column.data());
    if (!(rcond >= min_rcond)) return {SpdFailure::kIllConditioned, row, rcond};
    solve_row<T>(l, n, b.row(row).data(), node.value.row(row).data());
  }
  return {};
}

// Solves the rows of block r with factors already checked.
template <typename T>
SpdFailure solve_block(const Matrix<T>& factors, const Matrix<T>& b, Matrix<T>& x, RowBlock r) {
  for (Eigen::Index row = r.begin; row < r.end; ++row) {
    if (!b.row(row).allFinite()) return {SpdFailure::kNonFiniteRhs, row};
    solve_row<T>(factors.row(row).data(), b.cols(), b.row(row).data(), x.row(row).data());
  }
  return {};
}

// Runs block(part, rows of the part) over the batch split across the engine's threads (rows are
// independent, so the bits do not depend on the split); returns the first row's failure.
template <typename Block>
SpdFailure over_row_blocks(Eigen::Index rows, Block&& block) {
  const int parts = parts_for(rows);
  thread_local std::vector<SpdFailure> caller_failures;  // grows once to the thread count
  std::vector<SpdFailure>& failures = caller_failures;   // the caller's, not each worker's
  failures.assign(std::size_t(parts), SpdFailure{});
  parallel_for(parts, [&failures, &block, rows, parts](int p) {
    failures[std::size_t(p)] = block(p, row_block(rows, parts, p));
  });
  for (int p = 0; p < parts; ++p) {
    if (failures[std::size_t(p)].kind != SpdFailure::kNone) return failures[std::size_t(p)];
  }
  return {};
}

// Records in the node which matrix its factors are of, and where they are.
template <typename T>
void remember_factors(Node<T>& node, const Var<T>& a, const Matrix<T>& factors) {
  SpdFactors<T>& state = node.template state_for<SpdFactors<T>>();
  state.matrix = &a.node();
  state.generation = a.node().generation;
  state.factors = &factors;
}

// Factors every row of sym(A) into the node, checks it, and solves.
template <typename T>
SpdFailure factor_and_solve(const Var<T>& a, const Matrix<T>& b, Node<T>& node, double min_rcond) {
  const Eigen::Index n = b.cols(), rows = b.rows();
  node.buffers.resize(std::size_t(1 + parts_for(rows)));
  node.buffers[kFactors].resize(rows, n * n);
  node.value.resize(rows, n);
  remember_factors(node, a, node.buffers[kFactors]);
  return over_row_blocks(rows, [&](int p, RowBlock r) {
    Matrix<T>& column = node.buffers[std::size_t(1 + p)];
    column.resize(1, n);
    return factor_and_solve_block<T>(a.value(), b, node, r, column, min_rcond);
  });
}

// Solves with the factors of an earlier solve of `a`, which this node hands on to its own
// backward in turn.
template <typename T>
SpdFailure solve_factored(const Matrix<T>& factors, const Var<T>& a, const Matrix<T>& b,
                          Node<T>& node) {
  remember_factors(node, a, factors);
  node.value.resize(b.rows(), b.cols());
  return over_row_blocks(
      b.rows(), [&](int, RowBlock r) { return solve_block<T>(factors, b, node.value, r); });
}

template <typename T>
void throw_spd_failure(const SpdFailure& bad, Eigen::Index rows,
                       double min_rcond = double(kBatchedSolveMinRcond<T>)) {
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
          bad.row, rows, bad.rcond, min_rcond));
  }
}

// S x = b with S = sym(A): gb = S^-1 g (with this solve's factors), and <g, dx> = -<gb, sym(dA)
// x> = -<sym(gb x^T), dA>.
template <typename T>
void spd_solve_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>& a = n.inputs[0];
  const Var<T> x = Var<T>::of(n);
  const Var<T> gb = batched_spd_solve_factored(a, g, x);
  if (s.wants(0)) s.add(0, (batched_outer(gb, x) + batched_outer(x, gb)) * T(-0.5));
  if (s.wants(1)) s.add(1, gb);
}

template <typename T>
void check_shapes(const Var<T>& a, const Var<T>& b) {
  const Eigen::Index n = b.cols();
  HNN_AD_CHECK(a.rows() == b.rows() && n > 0 && a.cols() == n * n,
               "batched_spd_solve: blocks {} do not match right-hand sides {} (expected {}: one "
               "{}x{} block per row)",
               a.shape(), b.shape(), shape_str(b.rows(), n * n), n, n);
}

}  // namespace

template <typename T>
Var<T> batched_spd_solve(const Var<T>& a, const Var<T>& b, double min_rcond) {
  check_shapes(a, b);
  Node<T>& node = detail::record<T>("batched_spd_solve", {a, b}, spd_solve_backward<T>);
  throw_spd_failure<T>(factor_and_solve<T>(a, b.value(), node, min_rcond), a.rows(), min_rcond);
  return Var<T>::of(node);
}

template <typename T>
Var<T> batched_spd_solve_factored(const Var<T>& a, const Var<T>& b, const Var<T>& factored) {
  check_shapes(a, b);
  const Node<T>& earlier = factored.node();
  const SpdFactors<T>* state = earlier.template holds_state<SpdFactors<T>>()
                                   ? &earlier.template state_as<SpdFactors<T>>()
                                   : nullptr;
  HNN_AD_CHECK(state && state->matrix == &a.node() && state->generation == a.node().generation,
               "batched_spd_solve_factored: the factored solve given ({}) did not solve with this "
               "matrix",
               earlier.op);
  Node<T>& node = detail::record<T>("batched_spd_solve", {a, b}, spd_solve_backward<T>);
  throw_spd_failure<T>(solve_factored<T>(*state->factors, a, b.value(), node), a.rows());
  return Var<T>::of(node);
}

#define HNN_INSTANTIATE(T)                                                 \
  template Var<T> batched_spd_solve(const Var<T>&, const Var<T>&, double); \
  template Var<T> batched_spd_solve_factored(const Var<T>&, const Var<T>&, const Var<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
