// The fused tanh-MLP ops. Notation as in mlp_ops.h, with hidden layers k = 1..L-1, s_k = 1 - h_k^2
// (tanh' at layer k), and for the input gradient:
//   a_{L-1} = W_L^T (every row),  d_k = a_k * s_k,  a_{k-1} = d_k W_k^T,  dy/dx = a_0.
// Its backward, given G = dL/da_0, runs up the gradient chain and then down the forward chain:
//   abar_0 = G;  dbar_k = abar_{k-1} W_k;  dW_k += abar_{k-1}^T d_k;  abar_k = dbar_k * s_k;
//   hbar_k = -2 h_k a_k dbar_k;  dW_L = colsum(abar_{L-1})^T;
//   then zbar_k = hbar_k * s_k (hbar_k plus zbar_{k+1} W_{k+1}^T from above), dW_k += h_{k-1}^T
//   zbar_k, db_k = colsum(zbar_k), dx = zbar_1 W_1^T.
// Six GEMMs of R x n x n per step for two hidden layers of width n: the minimum for this work.

#include <bit>
#include <utility>

#include "autodiff/gemm.h"
#include "autodiff/mlp_ops.h"
#include "autodiff/op_builder.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"
#include "autodiff/row_kernels.h"

namespace hnn::ad {

void detail::init_gemm() {
#ifdef HNN_HAVE_OPENBLAS
  static const bool once = [] {
    openblas_set_num_threads(1);
    return true;
  }();
  (void)once;
#endif
}

namespace {

using Eigen::Index;

// tanh in place, vectorised for both types; 2 / (1 + e^-2z) - 1 saturates correctly at +-1.
template <typename Block>
void tanh_in_place(Block&& z) {
  using T = typename std::decay_t<Block>::Scalar;
  if constexpr (std::is_same_v<T, float>) {
    z = z.array().tanh().matrix();
  } else {
    z.array() = T(2) / (T(1) + (T(-2) * z.array()).exp()) - T(1);
  }
}

// The layers of a fused node. Inputs: x, W_1..W_L, then the biases that exist, in layer order.
// saved[0] = L, saved[1] = bit mask of the layers with a bias (bit i: layer i + 1).
template <typename T>
struct Layers {
  const Node<T>& node;
  int count = int(node.saved[0]);
  unsigned mask = unsigned(node.saved[1]);

  // Layer i in 1..L.
  int weight_input(int i) const { return i; }
  int bias_input(int i) const {
    if (!((mask >> (i - 1)) & 1u)) return -1;
    return 1 + count + std::popcount(mask & ((1u << (i - 1)) - 1u));
  }
  const Var<T>& weight(int i) const { return node.inputs[std::size_t(i)]; }
  const Matrix<T>& w(int i) const { return weight(i).value(); }
  const Var<T>* bias(int i) const {
    const int k = bias_input(i);
    return k < 0 ? nullptr : &node.inputs[std::size_t(k)];
  }
  const Matrix<T>& x() const { return node.inputs[0].value(); }
};

// Validates the layers and gathers the node's inputs (in a reused buffer: no allocation).
template <typename T>
std::span<const Var<T>> gather(const char* op, const Var<T>& x, const std::vector<Var<T>>& weights,
                               const std::vector<Var<T>>& biases, bool last_bias, unsigned& mask) {
  HNN_AD_CHECK(!weights.empty() && weights.size() == biases.size() && weights.size() <= 30,
               "{}: {} weights and {} biases (need 1 to 30 layers, one bias entry each)", op,
               weights.size(), biases.size());
  Index width = x.cols();
  for (std::size_t i = 0; i < weights.size(); ++i) {
    HNN_AD_CHECK(weights[i].rows() == width,
                 "{}: layer {} weight is {} but its input has {} columns", op, i + 1,
                 weights[i].shape(), width);
    width = weights[i].cols();
    if (biases[i].defined()) {
      HNN_AD_CHECK(biases[i].rows() == 1 && biases[i].cols() == width,
                   "{}: layer {} bias is {}, expected 1x{}", op, i + 1, biases[i].shape(), width);
    }
  }
  thread_local std::vector<Var<T>> inputs;
  inputs.clear();
  inputs.push_back(x);
  inputs.insert(inputs.end(), weights.begin(), weights.end());
  mask = 0;
  for (std::size_t i = 0; i < biases.size(); ++i) {
    if (!biases[i].defined() || (i + 1 == biases.size() && !last_bias)) continue;
    mask |= 1u << i;
    inputs.push_back(biases[i]);
  }
  return inputs;
}

// h_k = tanh(h_{k-1} W_k + b_k) for the hidden layers of rows [r.begin, r.end), into
// buffers[0..L-2].
template <typename T>
void hidden_rows(const Layers<T>& l, std::vector<Matrix<T>>& h, RowBlock r) {
  for (int k = 1; k < l.count; ++k) {
    auto out = h[std::size_t(k - 1)].middleRows(r.begin, r.size());
    const auto in = k == 1 ? l.x().middleRows(r.begin, r.size())
                           : std::as_const(h[std::size_t(k - 2)]).middleRows(r.begin, r.size());
    detail::gemm(in, false, l.w(k), false, out);
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
  void size_for(int layers) {
    if (int(dw.size()) < layers) {
      dw.resize(std::size_t(layers));
      db.resize(std::size_t(layers));
      hbar.resize(std::size_t(layers));
      grad.resize(std::size_t(layers));
    }
  }
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
  return detail::record<T>(op, std::span<const Var<T>>(), nullptr);
}

// Sums the parts' partial weight and bias gradients into gradient nodes and hands them on.
template <typename T>
void reduce_parameters(const Layers<T>& l, std::vector<PartSpace<T>>& space, int parts,
                       GradSink<T>& s, const char* op) {
  for (int k = 1; k <= l.count; ++k) {
    const int wi = l.weight_input(k), bi = l.bias_input(k);
    if (s.wants(wi)) {
      Node<T>& g = value_node<T>(op);
      g.value = space[0].dw[std::size_t(k)];
      for (int p = 1; p < parts; ++p) g.value += space[std::size_t(p)].dw[std::size_t(k)];
      s.add(wi, Var<T>::of(g));
    }
    if (bi >= 0 && s.wants(bi)) {
      Node<T>& g = value_node<T>(op);
      g.value = space[0].db[std::size_t(k)];
      for (int p = 1; p < parts; ++p) g.value += space[std::size_t(p)].db[std::size_t(k)];
      s.add(bi, Var<T>::of(g));
    }
  }
}

// ---- tanh_mlp ---------------------------------------------------------------------------------

// The recorded (differentiable) backward: the same backpropagation in ops, on a recomputed
// forward pass.
template <typename T>
void tanh_mlp_backward_recorded(const Layers<T>& l, const Var<T>& g, GradSink<T>& s) {
  std::vector<Var<T>> h{l.node.inputs[0]};
  for (int k = 1; k < l.count; ++k) {
    const Var<T>* b = l.bias(k);
    h.push_back(tanh(linear(h.back(), l.weight(k), b ? *b : Var<T>())));
  }
  Var<T> delta = g;
  for (int k = l.count; k >= 1; --k) {
    const Var<T>& prev = h[std::size_t(k - 1)];
    if (s.wants(l.weight_input(k))) s.add(l.weight_input(k), matmul(prev, delta, true, false));
    if (l.bias_input(k) >= 0 && s.wants(l.bias_input(k))) s.add(l.bias_input(k), sum_rows(delta));
    if (k > 1) {
      delta = tanh_backward(matmul(delta, l.weight(k), false, true), prev);
    } else if (s.wants(0)) {
      s.add(0, matmul(delta, l.weight(1), false, true));
    }
  }
}

template <typename T>
void tanh_mlp_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Layers<T> l{n};
  if (grad_enabled()) return tanh_mlp_backward_recorded(l, g, s);
  const Index rows = g.rows();
  const int parts = parts_for(rows);
  std::vector<PartSpace<T>>& space = workspace<T>(parts, l.count);
  Node<T>* dx_node = s.wants(0) ? &value_node<T>("tanh_mlp_grad") : nullptr;
  Matrix<T>* dx = dx_node ? &dx_node->value : nullptr;
  if (dx) dx->resize(rows, l.x().cols());
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    PartSpace<T>& w = space[std::size_t(p)];
    Matrix<T>* delta = &w.grad[std::size_t(l.count)];
    *delta = g.value().middleRows(r.begin, r.size());
    for (int k = l.count; k >= 1; --k) {
      const auto prev = k == 1 ? l.x().middleRows(r.begin, r.size())
                               : n.buffers[std::size_t(k - 2)].middleRows(r.begin, r.size());
      w.dw[std::size_t(k)].resize(prev.cols(), delta->cols());
      detail::gemm(prev, true, *delta, false, w.dw[std::size_t(k)]);
      if (l.bias_input(k) >= 0) {
        w.db[std::size_t(k)].resize(1, delta->cols());
        detail::column_sums(*delta, w.db[std::size_t(k)]);
      }
      if (k > 1) {
        Matrix<T>* next = &w.grad[std::size_t(k - 1)];
        next->resize(delta->rows(), l.w(k).rows());
        detail::gemm(*delta, false, l.w(k), true, *next);
        next->array() *= T(1) - prev.array().square();
        delta = next;
      } else if (dx) {
        detail::gemm(*delta, false, l.w(1), true, dx->middleRows(r.begin, r.size()));
      }
    }
  });
  if (dx_node) s.add(0, Var<T>::of(*dx_node));
  reduce_parameters(l, space, parts, s, "tanh_mlp_grad");
}

// ---- tanh_mlp_input_gradient ------------------------------------------------------------------

// buffers: h_k at [k - 1], a_k at [L - 2 + k], d_k at [2L - 3 + k], for k = 1..L-1.
template <typename T>
struct GradientBuffers {
  int count;
  std::size_t h(int k) const { return std::size_t(k - 1); }
  std::size_t a(int k) const { return std::size_t(count - 2 + k); }
  std::size_t d(int k) const { return std::size_t(2 * count - 3 + k); }
};

template <typename T>
void input_gradient_backward_recorded(const Layers<T>& l, const Var<T>& g, GradSink<T>& s) {
  const int L = l.count;
  std::vector<Var<T>> h{l.node.inputs[0]};
  for (int k = 1; k < L; ++k) {
    const Var<T>* b = l.bias(k);
    h.push_back(tanh(linear(h.back(), l.weight(k), b ? *b : Var<T>())));
  }
  std::vector<Var<T>> a(static_cast<std::size_t>(L)), d(static_cast<std::size_t>(L));
  a[std::size_t(L - 1)] = broadcast_to(transpose(l.weight(L)), g.rows(), l.weight(L).rows());
  for (int k = L - 1; k >= 1; --k) {
    d[std::size_t(k)] = tanh_backward(a[std::size_t(k)], h[std::size_t(k)]);
    a[std::size_t(k - 1)] = matmul(d[std::size_t(k)], l.weight(k), false, true);
  }
  const auto add_weight = [&](int k, const Var<T>& grad) {
    if (s.wants(l.weight_input(k))) s.add(l.weight_input(k), grad);
  };
  std::vector<Var<T>> hbar(static_cast<std::size_t>(L));
  Var<T> abar = g;
  for (int k = 1; k < L; ++k) {
    const Var<T> dbar = matmul(abar, l.weight(k));
    add_weight(k, matmul(abar, d[std::size_t(k)], true, false));
    hbar[std::size_t(k)] = T(-2) * h[std::size_t(k)] * a[std::size_t(k)] * dbar;
    abar = tanh_backward(dbar, h[std::size_t(k)]);
  }
  add_weight(L, transpose(sum_rows(abar)));
  Var<T> hb = hbar[std::size_t(L - 1)];
  for (int k = L - 1; k >= 1; --k) {
    const Var<T> zbar = tanh_backward(hb, h[std::size_t(k)]);
    add_weight(k, matmul(h[std::size_t(k - 1)], zbar, true, false));
    if (l.bias_input(k) >= 0 && s.wants(l.bias_input(k))) s.add(l.bias_input(k), sum_rows(zbar));
    if (k > 1) {
      hb = hbar[std::size_t(k - 1)] + matmul(zbar, l.weight(k), false, true);
    } else if (s.wants(0)) {
      s.add(0, matmul(zbar, l.weight(1), false, true));
    }
  }
}

template <typename T>
void input_gradient_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Layers<T> l{n};
  if (grad_enabled()) return input_gradient_backward_recorded(l, g, s);
  const int L = l.count;
  const GradientBuffers<T> at{L};
  const Index rows = g.rows();
  const int parts = parts_for(rows);
  std::vector<PartSpace<T>>& space = workspace<T>(parts, L);
  // With no hidden layer dy/dx = W^T does not depend on x.
  Node<T>* dx_node = s.wants(0) && L > 1 ? &value_node<T>("tanh_mlp_input_gradient_grad") : nullptr;
  if (dx_node) dx_node->value.resize(rows, l.x().cols());
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    const auto block = [&](std::size_t i) { return n.buffers[i].middleRows(r.begin, r.size()); };
    PartSpace<T>& w = space[std::size_t(p)];
    Matrix<T>* abar = &w.grad[0];
    *abar = g.value().middleRows(r.begin, r.size());
    for (int k = 1; k < L; ++k) {  // up the gradient chain; dbar_k becomes abar_k in place
      const auto hk = block(at.h(k));
      Matrix<T>* dbar = &w.grad[std::size_t(k)];
      dbar->resize(abar->rows(), l.w(k).cols());
      detail::gemm(*abar, false, l.w(k), false, *dbar);
      w.dw[std::size_t(k)].resize(abar->cols(), l.w(k).cols());
      detail::gemm(*abar, true, block(at.d(k)), false, w.dw[std::size_t(k)]);
      w.hbar[std::size_t(k)].resize(dbar->rows(), dbar->cols());
      w.hbar[std::size_t(k)].array() = T(-2) * hk.array() * block(at.a(k)).array() * dbar->array();
      dbar->array() *= T(1) - hk.array().square();
      abar = dbar;
    }
    w.dw[std::size_t(L)].resize(abar->cols(), 1);
    detail::column_sums(*abar, w.dw[std::size_t(L)].col(0).transpose());
    Matrix<T>* hb = &w.hbar[std::size_t(L - 1)];
    for (int k = L - 1; k >= 1; --k) {  // down the forward chain; zbar_k in place of hbar_k
      hb->array() *= T(1) - block(at.h(k)).array().square();
      const auto prev = k == 1 ? l.x().middleRows(r.begin, r.size()) : block(at.h(k - 1));
      detail::gemm(prev, true, *hb, false, w.dw[std::size_t(k)], T(1));
      if (l.bias_input(k) >= 0) {
        w.db[std::size_t(k)].resize(1, hb->cols());
        detail::column_sums(*hb, w.db[std::size_t(k)]);
      }
      if (k > 1) {
        detail::gemm(*hb, false, l.w(k), true, w.hbar[std::size_t(k - 1)], T(1));
        hb = &w.hbar[std::size_t(k - 1)];
      } else if (dx_node) {
        detail::gemm(*hb, false, l.w(1), true, dx_node->value.middleRows(r.begin, r.size()));
      }
    }
  });
  if (dx_node) s.add(0, Var<T>::of(*dx_node));
  reduce_parameters(l, space, parts, s, "tanh_mlp_input_gradient_grad");
}

}  // namespace

template <typename T>
Var<T> tanh_mlp(const Var<T>& x, const std::vector<Var<T>>& weights,
                const std::vector<Var<T>>& biases) {
  detail::init_gemm();
  unsigned mask = 0;
  const auto inputs = gather("tanh_mlp", x, weights, biases, /*last_bias=*/true, mask);
  Node<T>& node = detail::record<T>("tanh_mlp", inputs, tanh_mlp_backward<T>);
  if (node.inputs.empty()) node.inputs.assign(inputs.begin(), inputs.end());  // values only
  node.saved = {double(weights.size()), double(mask), 0.0};
  const Layers<T> l{node};
  const Index rows = x.rows();
  node.buffers.resize(std::size_t(l.count - 1));
  for (int k = 1; k < l.count; ++k) node.buffers[std::size_t(k - 1)].resize(rows, l.w(k).cols());
  node.value.resize(rows, l.w(l.count).cols());
  const int parts = parts_for(rows);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    hidden_rows(l, node.buffers, r);
    const int L = l.count;
    auto out = node.value.middleRows(r.begin, r.size());
    if (L == 1) {
      detail::gemm(l.x().middleRows(r.begin, r.size()), false, l.w(1), false, out);
    } else {
      detail::gemm(std::as_const(node.buffers[std::size_t(L - 2)]).middleRows(r.begin, r.size()),
                   false, l.w(L), false, out);
    }
    if (const Var<T>* b = l.bias(L)) out.rowwise() += b->value().row(0);
  });
  return Var<T>::of(node);
}

template <typename T>
Var<T> tanh_mlp_input_gradient(const Var<T>& x, const std::vector<Var<T>>& weights,
                               const std::vector<Var<T>>& biases) {
  detail::init_gemm();
  unsigned mask = 0;
  const auto inputs =
      gather("tanh_mlp_input_gradient", x, weights, biases, /*last_bias=*/false, mask);
  HNN_AD_CHECK(weights.back().cols() == 1,
               "tanh_mlp_input_gradient: the MLP must have one output, its last weight is {}",
               weights.back().shape());
  Node<T>& node = detail::record<T>("tanh_mlp_input_gradient", inputs, input_gradient_backward<T>);
  if (node.inputs.empty()) node.inputs.assign(inputs.begin(), inputs.end());  // values only
  node.saved = {double(weights.size()), double(mask), 0.0};
  const Layers<T> l{node};
  const int L = l.count;
  const GradientBuffers<T> at{L};
  const Index rows = x.rows();
  node.buffers.resize(std::size_t(3 * (L - 1)));
  for (int k = 1; k < L; ++k) {
    for (std::size_t i : {at.h(k), at.a(k), at.d(k)}) node.buffers[i].resize(rows, l.w(k).cols());
  }
  node.value.resize(rows, x.cols());
  const int parts = parts_for(rows);
  parallel_for(parts, [&](int p) {
    const RowBlock r = row_block(rows, parts, p);
    const auto block = [&](std::size_t i) { return node.buffers[i].middleRows(r.begin, r.size()); };
    hidden_rows(l, node.buffers, r);
    auto out = node.value.middleRows(r.begin, r.size());
    const auto top = l.w(L).col(0).transpose();  // dy/dh_{L-1}, the same for every row
    if (L == 1) {
      detail::fill_rows(out, top);
      return;
    }
    detail::fill_rows(block(at.a(L - 1)), top);
    for (int k = L - 1; k >= 1; --k) {
      block(at.d(k)).array() = block(at.a(k)).array() * (T(1) - block(at.h(k)).array().square());
      if (k > 1) {
        detail::gemm(std::as_const(node.buffers[at.d(k)]).middleRows(r.begin, r.size()), false,
                     l.w(k), true, block(at.a(k - 1)));
      } else {
        detail::gemm(std::as_const(node.buffers[at.d(k)]).middleRows(r.begin, r.size()), false,
                     l.w(k), true, out);
      }
    }
  });
  return Var<T>::of(node);
}

#define HNN_INSTANTIATE(T)                                                                         \
  template Var<T> tanh_mlp(const Var<T>&, const std::vector<Var<T>>&, const std::vector<Var<T>>&); \
  template Var<T> tanh_mlp_input_gradient(const Var<T>&, const std::vector<Var<T>>&,               \
                                          const std::vector<Var<T>>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
