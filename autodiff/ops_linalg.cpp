// Matrix products, the fused linear layer, and transpose.

#include "autodiff/gemm.h"
#include "autodiff/op_builder.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"

namespace hnn::ad {

namespace {

// Multiply-adds below which a product stays on one thread: a parallel region (waking, claiming,
// joining) costs about what a thread does in this many, and the small products of constrained
// mechanics, a dozen per field evaluation, were each split in two.
constexpr Eigen::Index kParallelProduct = Eigen::Index(1) << 17;

// out = op(a) op(b) without materialising a transpose, through the fused kernels' GEMM, with
// the output's rows (or, for a short wide output, its columns) split over the engine's threads.
template <typename T>
void product(const Matrix<T>& a, const Matrix<T>& b, bool ta, bool tb, Matrix<T>& out) {
  const Eigen::Index m = ta ? a.cols() : a.rows(), n = tb ? b.rows() : b.cols();
  out.resize(m, n);
  if ((ta ? a.rows() : a.cols()) == 0) {
    out.setZero();
    return;
  }
  const bool by_rows = m >= n;
  const Eigen::Index multiply_adds = m * n * (ta ? a.rows() : a.cols());
  const int parts = multiply_adds < kParallelProduct ? 1 : parts_for(by_rows ? m : n);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(by_rows ? m : n, parts, p);
    if (by_rows) {
      const auto rows = [&](const auto& lhs) {
        detail::gemm(lhs, ta, b, tb, out.middleRows(r.begin, r.size()));
      };
      if (ta)
        rows(a.middleCols(r.begin, r.size()));
      else
        rows(a.middleRows(r.begin, r.size()));
    } else {
      const auto cols = [&](const auto& rhs) {
        detail::gemm(a, ta, rhs, tb, out.middleCols(r.begin, r.size()));
      };
      if (tb)
        cols(b.middleRows(r.begin, r.size()));
      else
        cols(b.middleCols(r.begin, r.size()));
    }
  });
}

// C = A' B' with A' = op(A), B' = op(B): dA' = G B'^T, dB' = A'^T G, transposed back when the
// operand was used transposed. Every case is one matmul with flags.
template <typename T>
void matmul_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&a = n.inputs[0], &b = n.inputs[1];
  const bool ta = n.saved[0] != 0, tb = n.saved[1] != 0;
  if (s.wants(0)) s.add(0, ta ? matmul(b, g, tb, true) : matmul(g, b, false, !tb));
  if (s.wants(1)) s.add(1, tb ? matmul(g, a, true, ta) : matmul(a, g, !ta, false));
}

template <typename T>
void linear_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&x = n.inputs[0], &w = n.inputs[1];
  if (s.wants(0)) s.add(0, matmul(g, w, false, true));
  if (s.wants(1)) s.add(1, matmul(x, g, true, false));
  if (n.inputs.size() > 2 && s.wants(2)) s.add(2, sum_rows(g));
}

}  // namespace

template <typename T>
Var<T> matmul(const Var<T>& a, const Var<T>& b, bool ta, bool tb) {
  const Eigen::Index inner_a = ta ? a.rows() : a.cols(), inner_b = tb ? b.cols() : b.rows();
  HNN_AD_CHECK(inner_a == inner_b, "matmul: shapes {}{} and {}{} do not agree", a.shape(),
               ta ? "^T" : "", b.shape(), tb ? "^T" : "");
  Node<T>& node = detail::record<T>("matmul", {a, b}, matmul_backward<T>);
  node.saved = {double(ta), double(tb), 0.0};
  product<T>(a.value(), b.value(), ta, tb, node.value);
  return Var<T>::of(node);
}

template <typename T>
Var<T> transpose(const Var<T>& a) {
  Node<T>& node = detail::record<T>(
      "transpose", {a},
      [](const Node<T>&, const Var<T>& g, GradSink<T>& s) { s.add(0, transpose(g)); });
  node.value = a.value().transpose();
  return Var<T>::of(node);
}

template <typename T>
Var<T> linear(const Var<T>& x, const Var<T>& w, const Var<T>& b) {
  HNN_AD_CHECK(x.cols() == w.rows(), "linear: input {} does not match weight {}", x.shape(),
               w.shape());
  if (b.defined()) {
    HNN_AD_CHECK(b.rows() == 1 && b.cols() == w.cols(),
                 "linear: bias {} does not match weight {} (expected 1x{})", b.shape(), w.shape(),
                 w.cols());
  }
  Node<T>& node = b.defined() ? detail::record<T>("linear", {x, w, b}, linear_backward<T>)
                              : detail::record<T>("linear", {x, w}, linear_backward<T>);
  product<T>(x.value(), w.value(), false, false, node.value);
  if (b.defined()) node.value.rowwise() += b.value().row(0);
  return Var<T>::of(node);
}

#define HNN_INSTANTIATE(T)                                          \
  template Var<T> matmul(const Var<T>&, const Var<T>&, bool, bool); \
  template Var<T> transpose(const Var<T>&);                         \
  template Var<T> linear(const Var<T>&, const Var<T>&, const Var<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
