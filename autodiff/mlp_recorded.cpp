// The fused tanh-MLP ops' recorded backward passes: the formulas of mlp_kernels.cpp written in
// differentiable ops on a recomputed forward pass, used when the backward itself is recorded
// (create_graph), so that derivatives of any order work. The recomputed h_k equal the fused
// forward's bit for bit (same GEMM on the same row blocks, the one tanh kernel).

#include <cassert>

#include "autodiff/mlp_layers.h"
#include "autodiff/ops.h"

namespace hnn::ad::detail {

namespace {

// The per-layer handles of a recorded backward, kept per thread so that a warmed-up step of
// third order (an LNN's training step) allocates nothing. A Lease empties them on exit, so no
// handle (the weights are leaves) outlives the call. The recorded backwards record plain ops
// only, never a sweep, so they do not nest.
template <typename T>
struct Scratch {
  std::vector<Var<T>> h, a, d, hbar;
  bool busy = false;

  class Lease {
   public:
    Lease() : s_(instance()) {
      assert(!s_.busy && "recorded MLP backwards do not nest");
      s_.busy = true;
    }
    ~Lease() {
      for (std::vector<Var<T>>* v : {&s_.h, &s_.a, &s_.d, &s_.hbar}) v->clear();
      s_.busy = false;
    }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Scratch* operator->() { return &s_; }

   private:
    static Scratch& instance() {
      thread_local Scratch scratch;
      return scratch;
    }
    Scratch& s_;
  };
};

// h_0 = x, h_k = tanh(h_{k-1} W_k + b_k) for the hidden layers k = 1..L-1, as ops, into h.
template <typename T>
void hidden_layers(const MlpLayers<T>& l, std::vector<Var<T>>& h) {
  h.assign(1, l.x_var());
  for (int k = 1; k < l.count(); ++k) {
    const Var<T>* b = l.bias(k);
    h.push_back(tanh(linear(h.back(), l.weight(k), b ? *b : Var<T>())));
  }
}

// Adds make_grad() as the gradient of input i (-1: none), only when the sweep wants it.
template <typename T>
void add_if_wanted(GradSink<T>& s, int i, const auto& make_grad) {
  if (i >= 0 && s.wants(i)) s.add(i, make_grad());
}

// The input gradient's a_k and d_k of output j (mlp_kernels.cpp), as ops: a_{L-1} = W_L[:, j]^T
// on every row, d_k = a_k s_k, a_{k-1} = d_k W_k^T.
template <typename T>
void gradient_chain(const MlpLayers<T>& l, const std::vector<Var<T>>& h, Eigen::Index rows, int j,
                    std::vector<Var<T>>& a, std::vector<Var<T>>& d) {
  const int L = l.count();
  a.assign(std::size_t(L), Var<T>());
  d.assign(std::size_t(L), Var<T>());
  const Var<T>& top = l.weight(L);
  const Var<T> column = l.outputs() == 1 ? top : slice_cols(top, j, 1);
  a[std::size_t(L - 1)] = broadcast_to(transpose(column), rows, top.rows());
  for (int k = L - 1; k >= 1; --k) {
    d[std::size_t(k)] = tanh_backward(a[std::size_t(k)], h[std::size_t(k)]);
    a[std::size_t(k - 1)] = matmul(d[std::size_t(k)], l.weight(k), false, true);
  }
}

}  // namespace

template <typename T>
void tanh_mlp_backward_recorded(const MlpLayers<T>& l, const Var<T>& g, GradSink<T>& s) {
  typename Scratch<T>::Lease scratch;
  std::vector<Var<T>>& h = scratch->h;
  hidden_layers(l, h);
  Var<T> delta = g;
  for (int k = l.count(); k >= 1; --k) {
    const Var<T>& prev = h[std::size_t(k - 1)];
    add_if_wanted(s, l.weight_input(k), [&] { return matmul(prev, delta, true, false); });
    add_if_wanted(s, l.bias_input(k), [&] { return sum_rows(delta); });
    if (k > 1) {
      delta = tanh_backward(matmul(delta, l.weight(k), false, true), prev);
    } else {
      add_if_wanted(s, 0, [&] { return matmul(delta, l.weight(1), false, true); });
    }
  }
}

template <typename T>
void input_gradient_backward_recorded(const MlpLayers<T>& l, const Var<T>& g, GradSink<T>& s) {
  const int L = l.count();
  typename Scratch<T>::Lease scratch;
  std::vector<Var<T>>&h = scratch->h, &a = scratch->a, &d = scratch->d, &hbar = scratch->hbar;
  hidden_layers(l, h);
  hbar.assign(std::size_t(L), Var<T>());
  const int m = l.outputs();
  const Eigen::Index in = l.x().cols();
  for (int j = 0; j < m; ++j) {  // up the gradient chain of every output; the sink sums
    gradient_chain(l, h, g.rows(), j, a, d);
    Var<T> abar = m == 1 ? g : slice_cols(g, j * in, in);
    for (int k = 1; k < L; ++k) {
      const Var<T> dbar = matmul(abar, l.weight(k));
      add_if_wanted(s, l.weight_input(k),
                    [&] { return matmul(abar, d[std::size_t(k)], true, false); });
      const Var<T> term = T(-2) * h[std::size_t(k)] * a[std::size_t(k)] * dbar;
      hbar[std::size_t(k)] = j == 0 ? term : hbar[std::size_t(k)] + term;
      abar = tanh_backward(dbar, h[std::size_t(k)]);
    }
    add_if_wanted(s, l.weight_input(L), [&] {
      const Var<T> column = transpose(sum_rows(abar));
      return m == 1 ? column : pad_cols(column, j, m);
    });
  }
  Var<T> hb = hbar[std::size_t(L - 1)];  // down the forward chain (hbar is linear: once)
  for (int k = L - 1; k >= 1; --k) {
    const Var<T> zbar = tanh_backward(hb, h[std::size_t(k)]);
    add_if_wanted(s, l.weight_input(k),
                  [&] { return matmul(h[std::size_t(k - 1)], zbar, true, false); });
    add_if_wanted(s, l.bias_input(k), [&] { return sum_rows(zbar); });
    if (k > 1) {
      hb = hbar[std::size_t(k - 1)] + matmul(zbar, l.weight(k), false, true);
    } else {
      add_if_wanted(s, 0, [&] { return matmul(zbar, l.weight(1), false, true); });
    }
  }
}

#define HNN_INSTANTIATE(T)                                                                    \
  template void tanh_mlp_backward_recorded(const MlpLayers<T>&, const Var<T>&, GradSink<T>&); \
  template void input_gradient_backward_recorded(const MlpLayers<T>&, const Var<T>&, GradSink<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad::detail
