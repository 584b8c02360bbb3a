// The fused tanh-MLP ops' hand-written kernels: forward passes and first-order backward passes
// on row blocks of the batch, one per engine thread, through the GEMM of gemm.h. Values only:
// when a backward must be recorded, ops_mlp.cpp calls mlp_recorded.cpp instead.
//
// Notation as in mlp_ops.h, with s_k = 1 - h_k^2 (tanh' at hidden layer k). The input gradient
// of output j: a_{L-1} = W_L[:, j]^T (every row), d_k = a_k * s_k, a_{k-1} = d_k W_k^T,
// dy_j/dx = a_0. Its backward, given G = dL/da_0, runs up the gradient chain of every output and
// then down the forward chain once:
//   abar_0 = G;  dbar_k = abar_{k-1} W_k;  dW_k += abar_{k-1}^T d_k;  abar_k = dbar_k * s_k;
//   hbar_k += -2 h_k a_k dbar_k;  dW_L[:, j] = colsum(abar_{L-1})^T;
//   then zbar_k = hbar_k * s_k (hbar_k plus zbar_{k+1} W_{k+1}^T from above), dW_k += h_{k-1}^T
//   zbar_k, db_k = colsum(zbar_k), dx = zbar_1 W_1^T.
// Six GEMMs of R x n x n per step for two hidden layers of width n: the minimum for this work.
// Each further output adds three (the forward and the way down are shared: hbar is linear), where
// one op per output would add six.

#include <utility>

#include "autodiff/gemm.h"
#include "autodiff/mlp_layers.h"
#include "autodiff/op_builder.h"
#include "autodiff/parallel.h"
#include "autodiff/row_kernels.h"
#include "autodiff/tanh_kernel.h"

namespace hnn::ad::detail {

namespace {

using Eigen::Index;

// Rows r of h_k: x for k = 0, else the hidden layer's buffer (h_k sits at index k - 1 in both
// ops' buffers).
template <typename T>
auto hidden_block(const MlpLayers<T>& l, const std::vector<Matrix<T>>& buffers, int k, RowBlock r) {
  const Matrix<T>& h = k == 0 ? l.x() : buffers[std::size_t(k - 1)];
  return h.middleRows(r.begin, r.size());
}

// h_k = tanh(h_{k-1} W_k + b_k) for the hidden layers, rows r, into buffers[k - 1].
template <typename T>
void hidden_rows(const MlpLayers<T>& l, std::vector<Matrix<T>>& buffers, RowBlock r) {
  for (int k = 1; k < l.count(); ++k) {
    auto out = buffers[std::size_t(k - 1)].middleRows(r.begin, r.size());
    gemm(hidden_block(l, std::as_const(buffers), k - 1, r), false, l.w(k), false, out);
    if (const Var<T>* b = l.bias(k)) out.rowwise() += b->value().row(0);
    tanh_in_place(out);
  }
}

// One part's scratch, owned by the thread that runs the op (workers write into it).
template <typename T>
struct PartSpace {
  // Per layer, so that every buffer keeps one shape from step to step (no reallocation):
  // partial weight and bias gradients, hbar_k, and the gradient propagated to layer k.
  std::vector<Matrix<T>> dw, db, hbar, grad;
  Matrix<T> sums;  // a row of column sums, before it goes into a column of dW_L
  // Per layer: the sweep's gradient sum that the weight's products are added into (Note [Sums
  // added into in place] in grad.cpp), or null for the partial dw; and the next product's beta.
  std::vector<Matrix<T>*> dw_sum;
  std::vector<T> dw_beta;
  void size_for(int layers) {
    if (int(dw.size()) < layers) {
      dw.resize(std::size_t(layers));
      db.resize(std::size_t(layers));
      hbar.resize(std::size_t(layers));
      grad.resize(std::size_t(layers));
      dw_sum.resize(std::size_t(layers));
      dw_beta.resize(std::size_t(layers));
    }
  }
  Matrix<T>& weight_gradient(int k) {
    Matrix<T>* sum = dw_sum[std::size_t(k)];
    return sum ? *sum : dw[std::size_t(k)];
  }
  // beta for the next product into layer k's weight gradient: 0 for a partial's first.
  T take_beta(int k) { return std::exchange(dw_beta[std::size_t(k)], T(1)); }
};

template <typename T>
std::vector<PartSpace<T>>& workspace(int parts, int layers) {
  thread_local std::vector<PartSpace<T>> space;
  if (int(space.size()) < parts) space.resize(std::size_t(parts));
  for (int p = 0; p < parts; ++p) space[std::size_t(p)].size_for(layers + 1);
  return space;
}

// A node on the tape for a gradient computed in place (values only: the sweep does not record).
template <typename T>
Node<T>& value_node(const char* op) {
  return record<T>(op, std::span<const Var<T>>(), nullptr);
}

// The sum of the parts' partial gradients of one parameter, handed on as input `input`. One
// part's is swapped into the node, not copied: the node's old buffer (this slot's gradient of the
// last step, the same shape) becomes the part's next scratch, so nothing is allocated. Two
// parts' are added in one pass.
template <typename T>
void add_reduced(std::vector<PartSpace<T>>& space, int parts,
                 std::vector<Matrix<T>> PartSpace<T>::*partial, int k, int input, GradSink<T>& s,
                 const char* op) {
  Node<T>& g = value_node<T>(op);
  const auto part = [&](int p) -> Matrix<T>& {
    return (space[std::size_t(p)].*partial)[std::size_t(k)];
  };
  if (parts == 1) {
    g.value.swap(part(0));
  } else {
    // Split over the threads when big (a 256 x 256 weight's sum, left on the calling thread,
    // idled the others for 1% of a CHNN step); each element is summed in the same order either
    // way.
    g.value.resize(part(0).rows(), part(0).cols());
    for_element_blocks(g.value.size(), [&](RowBlock e) {
      flat(g.value, e) = flat(part(0), e) + flat(part(1), e);
      for (int p = 2; p < parts; ++p) flat(g.value, e) += flat(part(p), e);
    });
  }
  s.add(input, Var<T>::of(g));
}

// Where each part's weight gradients go. With one part, the products of layers 1 .. last add
// into the sweep's sums when it allows (a values-only sweep): no partial to zero and hand on.
// Otherwise into the parts' partials, each sized for its first product (beta 0).
template <typename T>
void route_weight_gradients(const MlpLayers<T>& l, std::vector<PartSpace<T>>& space, int parts,
                            int last, GradSink<T>& s) {
  for (int p = 0; p < parts; ++p) {
    PartSpace<T>& w = space[std::size_t(p)];
    for (int k = 1; k <= l.count(); ++k) {
      const int wi = l.weight_input(k);
      Matrix<T>* sum = parts == 1 && k <= last && s.wants(wi) ? s.sum_into(wi) : nullptr;
      w.dw_sum[std::size_t(k)] = sum;
      w.dw_beta[std::size_t(k)] = sum ? T(1) : T(0);
      if (!sum) w.dw[std::size_t(k)].resize(l.w(k).rows(), l.w(k).cols());
    }
  }
}

// Sums the parts' partial weight and bias gradients into gradient nodes and hands them on.
template <typename T>
void reduce_parameters(const MlpLayers<T>& l, std::vector<PartSpace<T>>& space, int parts,
                       GradSink<T>& s, const char* op) {
  for (int k = 1; k <= l.count(); ++k) {
    const int wi = l.weight_input(k), bi = l.bias_input(k);
    const bool added = space[0].dw_sum[std::size_t(k)] != nullptr;
    if (!added && s.wants(wi)) add_reduced(space, parts, &PartSpace<T>::dw, k, wi, s, op);
    if (bi >= 0 && s.wants(bi)) add_reduced(space, parts, &PartSpace<T>::db, k, bi, s, op);
  }
}

// Whether the sweep wants any weight or bias gradient. A Jacobian with respect to the input
// alone (the LNN's Hessian blocks, evaluated on every rollout state) wants none: its kernels then
// skip the partial parameter gradients, GEMMs the size of the weights (half an LNN evaluation's
// time went to them and to zeroing their outputs).
template <typename T>
bool wants_parameters(const MlpLayers<T>& l, const GradSink<T>& s) {
  for (int k = 1; k <= l.count(); ++k) {
    const int bi = l.bias_input(k);
    if (s.wants(l.weight_input(k)) || (bi >= 0 && s.wants(bi))) return true;
  }
  return false;
}

// ---- tanh_mlp -----------------------------------------------------------------------------------

// Backpropagation over rows r: partial parameter gradients into w, dx rows into dx (if wanted).
template <typename T>
void backprop_rows(const MlpLayers<T>& l, const Node<T>& n, const Var<T>& g, PartSpace<T>& w,
                   RowBlock r, Matrix<T>* dx, bool params) {
  Matrix<T>* delta = &w.grad[std::size_t(l.count())];
  *delta = g.value().middleRows(r.begin, r.size());
  for (int k = l.count(); k >= 1; --k) {
    const auto prev = hidden_block(l, n.buffers, k - 1, r);
    if (params) {
      gemm(prev, true, *delta, false, w.weight_gradient(k), w.take_beta(k));
      if (l.bias_input(k) >= 0) {
        w.db[std::size_t(k)].resize(1, delta->cols());
        column_sums(*delta, w.db[std::size_t(k)]);
      }
    }
    if (k > 1) {
      Matrix<T>* next = &w.grad[std::size_t(k - 1)];
      next->resize(delta->rows(), l.w(k).rows());
      gemm(*delta, false, l.w(k), true, *next);
      next->array() *= T(1) - prev.array().square();
      delta = next;
    } else if (dx) {
      gemm(*delta, false, l.w(1), true, dx->middleRows(r.begin, r.size()));
    }
  }
}

// ---- tanh_mlp_input_gradient ------------------------------------------------------------------

// Rows r of the input gradient's buffer i.
template <typename T>
auto rows_of(const Node<T>& n, std::size_t i, RowBlock r) {
  return n.buffers[i].middleRows(r.begin, r.size());
}

// Up the gradient chain of output j for rows r: dW_k += abar_{k-1}^T d_k, hbar_k, and column j
// of dW_L (each dbar_k becomes abar_k in place). Output 0 sets the sums, later outputs add.
template <typename T>
void up_the_gradient_chain(const MlpLayers<T>& l, const Node<T>& n, const Var<T>& g, int j,
                           PartSpace<T>& w, RowBlock r, bool params) {
  const GradientBuffers at{l.count(), l.outputs()};
  const Index in = l.x().cols();
  Matrix<T>* abar = &w.grad[0];
  *abar = g.value().block(r.begin, j * in, r.size(), in);
  for (int k = 1; k < l.count(); ++k) {
    const auto hk = rows_of(n, at.h(k), r);
    Matrix<T>* dbar = &w.grad[std::size_t(k)];
    dbar->resize(abar->rows(), l.w(k).cols());
    gemm(*abar, false, l.w(k), false, *dbar);
    if (params) {
      gemm(*abar, true, rows_of(n, at.d(k, j), r), false, w.weight_gradient(k), w.take_beta(k));
    }
    Matrix<T>& hbar = w.hbar[std::size_t(k)];
    hbar.resize(dbar->rows(), dbar->cols());
    const auto term = T(-2) * hk.array() * rows_of(n, at.a(k, j), r).array() * dbar->array();
    if (j == 0) {
      hbar.array() = term;
    } else {
      hbar.array() += term;
    }
    dbar->array() *= T(1) - hk.array().square();
    abar = dbar;
  }
  if (!params) return;
  // Summed into a contiguous row first: added straight into the column (a stride of m
  // elements), the sum did not vectorise and cost as much as a GEMM's packing.
  w.sums.resize(1, abar->cols());
  column_sums(*abar, w.sums);
  w.dw[std::size_t(l.count())].col(j) = w.sums.transpose();
}

// Down the forward chain for rows r: zbar_k in place of hbar_k, dW_k += h_{k-1}^T zbar_k, db_k,
// and dx rows into dx (if wanted).
template <typename T>
void down_the_forward_chain(const MlpLayers<T>& l, const Node<T>& n, PartSpace<T>& w, RowBlock r,
                            Matrix<T>* dx, bool params) {
  const GradientBuffers at{l.count(), l.outputs()};
  Matrix<T>* hb = &w.hbar[std::size_t(l.count() - 1)];
  for (int k = l.count() - 1; k >= 1; --k) {
    hb->array() *= T(1) - rows_of(n, at.h(k), r).array().square();
    if (params) {
      gemm(hidden_block(l, n.buffers, k - 1, r), true, *hb, false, w.weight_gradient(k),
           w.take_beta(k));
      if (l.bias_input(k) >= 0) {
        w.db[std::size_t(k)].resize(1, hb->cols());
        column_sums(*hb, w.db[std::size_t(k)]);
      }
    }
    if (k > 1) {
      gemm(*hb, false, l.w(k), true, w.hbar[std::size_t(k - 1)], T(1));
      hb = &w.hbar[std::size_t(k - 1)];
    } else if (dx) {
      gemm(*hb, false, l.w(1), true, dx->middleRows(r.begin, r.size()));
    }
  }
}

// dy_j/dx for rows r into the value's column block j, from the hidden layers already in the
// buffers: a_{L-1} = W_L[:, j]^T, then d_k = a_k s_k and a_{k-1} = d_k W_k^T down to a_0.
template <typename T>
void input_gradient_rows(const MlpLayers<T>& l, Node<T>& node, int j, RowBlock r) {
  const int L = l.count();
  const GradientBuffers at{L, l.outputs()};
  const Index in = l.x().cols();
  const auto block = [&](std::size_t i) { return node.buffers[i].middleRows(r.begin, r.size()); };
  auto out = node.value.block(r.begin, j * in, r.size(), in);
  const auto top = l.w(L).col(j).transpose();  // dy_j/dh_{L-1}, the same for every row
  if (L == 1) return fill_rows(out, top);
  fill_rows(block(at.a(L - 1, j)), top);
  for (int k = L - 1; k >= 1; --k) {
    block(at.d(k, j)).array() =
        block(at.a(k, j)).array() * (T(1) - block(at.h(k)).array().square());
    const auto d = std::as_const(node.buffers[at.d(k, j)]).middleRows(r.begin, r.size());
    if (k > 1) {
      gemm(d, false, l.w(k), true, block(at.a(k - 1, j)));
    } else {
      gemm(d, false, l.w(k), true, out);
    }
  }
}

}  // namespace

template <typename T>
void tanh_mlp_forward(const MlpLayers<T>& l, Node<T>& node) {
  const int L = l.count();
  const Index rows = l.x().rows();
  node.buffers.resize(std::size_t(L - 1));
  for (int k = 1; k < L; ++k) node.buffers[std::size_t(k - 1)].resize(rows, l.w(k).cols());
  node.value.resize(rows, l.w(L).cols());
  const int parts = parts_for(rows);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    hidden_rows(l, node.buffers, r);
    auto out = node.value.middleRows(r.begin, r.size());
    gemm(hidden_block(l, std::as_const(node.buffers), L - 1, r), false, l.w(L), false, out);
    if (const Var<T>* b = l.bias(L)) out.rowwise() += b->value().row(0);
  });
}

template <typename T>
void input_gradient_forward(const MlpLayers<T>& l, Node<T>& node) {
  const int L = l.count();
  const GradientBuffers at{L, l.outputs()};
  const Index rows = l.x().rows();
  node.buffers.resize(at.size());
  for (int k = 1; k < L; ++k) {
    node.buffers[at.h(k)].resize(rows, l.w(k).cols());
    for (int j = 0; j < at.columns; ++j) {
      for (std::size_t i : {at.a(k, j), at.d(k, j)}) node.buffers[i].resize(rows, l.w(k).cols());
    }
  }
  node.value.resize(rows, at.columns * l.x().cols());
  const int parts = parts_for(rows);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    hidden_rows(l, node.buffers, r);
    for (int j = 0; j < at.columns; ++j) input_gradient_rows(l, node, j, r);
  });
}

template <typename T>
void tanh_mlp_backward_kernel(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const MlpLayers<T> l = layers_of(n);
  const Index rows = g.rows();
  const int parts = parts_for(rows);
  std::vector<PartSpace<T>>& space = workspace<T>(parts, l.count());
  Node<T>* dx_node = s.wants(0) ? &value_node<T>("tanh_mlp_grad") : nullptr;
  if (dx_node) dx_node->value.resize(rows, l.x().cols());
  const bool params = wants_parameters(l, s);
  if (params) route_weight_gradients(l, space, parts, l.count(), s);
  parallel_for(parts, [&](int p) {
    backprop_rows(l, n, g, space[std::size_t(p)], row_block(rows, parts, p),
                  dx_node ? &dx_node->value : nullptr, params);
  });
  if (dx_node) s.add(0, Var<T>::of(*dx_node));
  if (params) reduce_parameters(l, space, parts, s, "tanh_mlp_grad");
}

template <typename T>
void input_gradient_backward_kernel(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const MlpLayers<T> l = layers_of(n);
  const Index rows = g.rows();
  const int parts = parts_for(rows);
  std::vector<PartSpace<T>>& space = workspace<T>(parts, l.count());
  // With no hidden layer dy/dx = W^T does not depend on x.
  const bool wants_dx = s.wants(0) && l.count() > 1;
  Node<T>* dx_node = wants_dx ? &value_node<T>("tanh_mlp_input_gradient_grad") : nullptr;
  if (dx_node) dx_node->value.resize(rows, l.x().cols());
  const bool params = wants_parameters(l, s);
  // The last layer's weight gradient is column sums set column by column: a partial.
  if (params) route_weight_gradients(l, space, parts, l.count() - 1, s);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    PartSpace<T>& w = space[std::size_t(p)];
    for (int j = 0; j < l.outputs(); ++j) up_the_gradient_chain(l, n, g, j, w, r, params);
    down_the_forward_chain(l, n, w, r, dx_node ? &dx_node->value : nullptr, params);
  });
  if (dx_node) s.add(0, Var<T>::of(*dx_node));
  if (params) reduce_parameters(l, space, parts, s, "tanh_mlp_input_gradient_grad");
}

#define HNN_INSTANTIATE(T)                                                             \
  template void tanh_mlp_forward(const MlpLayers<T>&, Node<T>&);                       \
  template void input_gradient_forward(const MlpLayers<T>&, Node<T>&);                 \
  template void tanh_mlp_backward_kernel(const Node<T>&, const Var<T>&, GradSink<T>&); \
  template void input_gradient_backward_kernel(const Node<T>&, const Var<T>&, GradSink<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad::detail
