// Elementwise ops: arithmetic with broadcasting, and the math and activation functions.

#include <cmath>

#include "autodiff/op_builder.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"
#include "autodiff/tanh_kernel.h"

namespace hnn::ad {

namespace {

// body(first_row, row_count) over row blocks of a rows x cols result, concurrently when it is
// big. Every element is computed by the same expression either way: results do not depend on
// the split.
template <typename Body>
void for_row_blocks(Eigen::Index rows, Eigen::Index cols, const Body& body) {
  const int parts = rows * cols >= kParallelElements ? parts_for(rows) : 1;
  if (parts <= 1) return body(Eigen::Index(0), rows);
  parallel_for(parts, [&](int i) {
    const RowBlock block = row_block(rows, parts, i);
    body(block.begin, block.size());
  });
}

// The broadcast size of one dimension, or -1 when the two sizes cannot be broadcast together.
Eigen::Index broadcast_dim(Eigen::Index a, Eigen::Index b) {
  if (a == b || b == 1) return a;
  return a == 1 ? b : -1;
}

// The broadcast shape of a and b, or an error naming the op and both shapes. The shapes are
// formatted for the error only: formatted up front, four strings per binary op were a tenth of
// the rollout step's small ops.
template <typename T>
std::pair<Eigen::Index, Eigen::Index> broadcast_shape(const char* op, const Var<T>& a,
                                                      const Var<T>& b) {
  const Eigen::Index rows = broadcast_dim(a.rows(), b.rows());
  const Eigen::Index cols = broadcast_dim(a.cols(), b.cols());
  HNN_AD_CHECK(rows >= 0 && cols >= 0, "{}: shapes {} and {} cannot be broadcast together", op,
               a.shape(), b.shape());
  return {rows, cols};
}

// out = f(a, b) elementwise, with a and b broadcast to out's shape.
template <typename T, typename F>
void apply_broadcast(const Matrix<T>& a, const Matrix<T>& b, Matrix<T>& out, Eigen::Index rows,
                     Eigen::Index cols, F f) {
  out.resize(rows, cols);
  if (a.rows() == rows && a.cols() == cols && b.rows() == rows && b.cols() == cols) {
    for_row_blocks(rows, cols, [&](Eigen::Index r, Eigen::Index n) {
      out.middleRows(r, n).array() = f(a.middleRows(r, n).array(), b.middleRows(r, n).array());
    });
  } else if (a.rows() == rows && a.cols() == cols && b.rows() == 1 && b.cols() == cols) {
    // a row broadcast (a bias, a scale): row by row, vectorised (replicate is not)
    for_row_blocks(rows, cols, [&](Eigen::Index r, Eigen::Index n) {
      for (Eigen::Index i = r; i < r + n; ++i)
        out.row(i).array() = f(a.row(i).array(), b.row(0).array());
    });
  } else if (b.rows() == rows && b.cols() == cols && a.rows() == 1 && a.cols() == cols) {
    for_row_blocks(rows, cols, [&](Eigen::Index r, Eigen::Index n) {
      for (Eigen::Index i = r; i < r + n; ++i)
        out.row(i).array() = f(a.row(0).array(), b.row(i).array());
    });
  } else {
    out.array() = f(a.replicate(rows / a.rows(), cols / a.cols()).array(),
                    b.replicate(rows / b.rows(), cols / b.cols()).array());
  }
}

// Reduces a gradient to the shape of the input it belongs to.
template <typename T>
Var<T> reduce_to(const Var<T>& g, const Var<T>& input) {
  return sum_to(g, input.rows(), input.cols());
}

template <typename T>
void add_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  if (s.wants(0)) s.add(0, reduce_to(g, n.inputs[0]));
  if (s.wants(1)) s.add(1, reduce_to(g, n.inputs[1]));
}
template <typename T>
void sub_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  if (s.wants(0)) s.add(0, reduce_to(g, n.inputs[0]));
  if (s.wants(1)) s.add(1, reduce_to(neg(g), n.inputs[1]));
}
template <typename T>
void mul_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&a = n.inputs[0], &b = n.inputs[1];
  if (s.wants(0)) s.add(0, reduce_to(g * b, a));
  if (s.wants(1)) s.add(1, reduce_to(g * a, b));
}
template <typename T>
void div_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>&a = n.inputs[0], &b = n.inputs[1];
  const Var<T> g_over_b = g / b;
  if (s.wants(0)) s.add(0, reduce_to(g_over_b, a));
  if (s.wants(1)) s.add(1, reduce_to(neg(g_over_b * Var<T>::of(n)), b));  // -g a / b^2
}

template <typename T, typename F>
Var<T> binary(const char* op, const Var<T>& a, const Var<T>& b, BackwardFn<T> backward, F f) {
  const auto [rows, cols] = broadcast_shape(op, a, b);
  Node<T>& node = detail::record<T>(op, {a, b}, backward);
  apply_broadcast<T>(a.value(), b.value(), node.value, rows, cols, f);
  return Var<T>::of(node);
}

// A unary op: value = f(x.value()), gradient given by `backward`.
template <typename T, typename F>
Var<T> unary(const char* op, const Var<T>& x, BackwardFn<T> backward, F f,
             std::array<double, 3> saved = {}) {
  Node<T>& node = detail::record<T>(op, {x}, backward);
  node.saved = saved;
  const Matrix<T>& in = x.value();
  node.value.resize(in.rows(), in.cols());
  for_row_blocks(in.rows(), in.cols(), [&](Eigen::Index r, Eigen::Index n) {
    node.value.middleRows(r, n) = f(in.middleRows(r, n).array()).matrix();
  });
  return Var<T>::of(node);
}

template <typename T>
const Var<T>& in0(const Node<T>& n) {
  return n.inputs[0];
}

}  // namespace

template <typename T>
Var<T> add(const Var<T>& a, const Var<T>& b) {
  return binary<T>("add", a, b, add_backward<T>, [](auto x, auto y) { return x + y; });
}
template <typename T>
Var<T> sub(const Var<T>& a, const Var<T>& b) {
  return binary<T>("sub", a, b, sub_backward<T>, [](auto x, auto y) { return x - y; });
}
template <typename T>
Var<T> mul(const Var<T>& a, const Var<T>& b) {
  return binary<T>("mul", a, b, mul_backward<T>, [](auto x, auto y) { return x * y; });
}
template <typename T>
Var<T> div(const Var<T>& a, const Var<T>& b) {
  return binary<T>("div", a, b, div_backward<T>, [](auto x, auto y) { return x / y; });
}

template <typename T>
Var<T> neg(const Var<T>& a) {
  return unary<T>(
      "neg", a, [](const Node<T>&, const Var<T>& g, GradSink<T>& s) { s.add(0, neg(g)); },
      [](auto x) { return -x; });
}

template <typename T>
Var<T> scale(const Var<T>& a, std::type_identity_t<T> k) {
  return unary<T>(
      "scale", a,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, scale(g, static_cast<T>(n.saved[0])));
      },
      [k](auto x) { return x * k; }, {double(k)});
}

template <typename T>
Var<T> shift(const Var<T>& a, std::type_identity_t<T> k) {
  return unary<T>(
      "shift", a, [](const Node<T>&, const Var<T>& g, GradSink<T>& s) { s.add(0, g); },
      [k](auto x) { return x + k; });
}

template <typename T>
Var<T> square(const Var<T>& x) {
  return unary<T>(
      "square", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, scale(g * in0(n), T(2))); },
      [](auto v) { return v.square(); });
}

template <typename T>
Var<T> pow(const Var<T>& x, std::type_identity_t<T> e) {
  return unary<T>(
      "pow", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        const T e = static_cast<T>(n.saved[0]);
        s.add(0, g * scale(pow(in0(n), e - T(1)), e));
      },
      [e](auto v) { return v.pow(e); }, {double(e)});
}

template <typename T>
Var<T> sqrt(const Var<T>& x) {
  return unary<T>(
      "sqrt", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, g / scale(Var<T>::of(n), T(2)));
      },
      [](auto v) { return v.sqrt(); });
}

template <typename T>
Var<T> exp(const Var<T>& x) {
  return unary<T>(
      "exp", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, g * Var<T>::of(n)); },
      [](auto v) { return v.exp(); });
}

template <typename T>
Var<T> log(const Var<T>& x) {
  return unary<T>(
      "log", x, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, g / in0(n)); },
      [](auto v) { return v.log(); });
}

template <typename T>
Var<T> sin(const Var<T>& x) {
  return unary<T>(
      "sin", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, g * cos(in0(n))); },
      [](auto v) { return v.sin(); });
}

template <typename T>
Var<T> cos(const Var<T>& x) {
  return unary<T>(
      "cos", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, neg(g * sin(in0(n)))); },
      [](auto v) { return v.cos(); });
}

template <typename T>
Var<T> tanh(const Var<T>& x) {
  Node<T>& node =
      detail::record<T>("tanh", {x}, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, tanh_backward(g, Var<T>::of(n)));
      });
  node.value.resize(x.rows(), x.cols());
  detail::tanh_values(x.value().data(), node.value.data(), x.value().size());
  return Var<T>::of(node);
}

namespace {
// d/dg [g (1 - y^2)] = 1 - y^2, d/dy = -2 y g.
template <typename T>
void tanh_backward_backward(const Node<T>& n, const Var<T>& gg, GradSink<T>& s) {
  const Var<T>&g = n.inputs[0], &y = n.inputs[1];
  if (s.wants(0)) s.add(0, tanh_backward(gg, y));
  if (s.wants(1)) s.add(1, scale(gg * g * y, T(-2)));
}
}  // namespace

template <typename T>
Var<T> tanh_backward(const Var<T>& g, const Var<T>& y) {
  HNN_AD_CHECK(g.rows() == y.rows() && g.cols() == y.cols(),
               "tanh_backward: gradient {} and output {} differ in shape", g.shape(), y.shape());
  Node<T>& node = detail::record<T>("tanh_backward", {g, y}, tanh_backward_backward<T>);
  node.value = (g.value().array() * (T(1) - y.value().array().square())).matrix();
  return Var<T>::of(node);
}

template <typename T>
Var<T> sigmoid(const Var<T>& x) {
  return unary<T>(
      "sigmoid", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        const Var<T> y = Var<T>::of(n);
        s.add(0, g * (y * (T(1) - y)));
      },
      [](auto v) { return T(1) / (T(1) + (-v).exp()); });
}

template <typename T>
Var<T> step(const Var<T>& x) {
  NoGradGuard constant_mask;
  // A scalar functor, whose loop GCC vectorises; Eigen 3.4 has no packet comparison, and its
  // (v > 0).cast<T>() ran one element at a time, 6x slower (ReLU's backward in the pixel step).
  return unary<T>("step", x, nullptr,
                  [](auto v) { return v.unaryExpr([](T a) { return a > T(0) ? T(1) : T(0); }); });
}

template <typename T>
Var<T> relu(const Var<T>& x) {
  return unary<T>(
      "relu", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, g * step(in0(n))); },
      [](auto v) { return v.max(T(0)); });
}

template <typename T>
Var<T> softplus(const Var<T>& x) {
  // log(1 + e^x) = max(x, 0) + log1p(e^-|x|): no overflow for large |x|.
  return unary<T>(
      "softplus", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) { s.add(0, g * sigmoid(in0(n))); },
      [](auto v) { return v.max(T(0)) + (-v.abs()).exp().log1p(); });
}

namespace {
// The negative branch of elu's derivatives: alpha e^x for x <= 0, 0 for x > 0. It is its own
// derivative, so elu is differentiable to any order: elu' = step(x) + elu_tail(x).
template <typename T>
Var<T> elu_tail(const Var<T>& x, T alpha) {
  return unary<T>(
      "elu_tail", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, g * elu_tail(in0(n), static_cast<T>(n.saved[0])));
      },
      [alpha](auto v) { return (v > T(0)).select(T(0), alpha * v.min(T(0)).exp()); },
      {double(alpha)});
}
}  // namespace

template <typename T>
Var<T> elu(const Var<T>& x, std::type_identity_t<T> alpha) {
  return unary<T>(
      "elu", x,
      [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        const Var<T>& x = in0(n);
        s.add(0, g * (step(x) + elu_tail(x, static_cast<T>(n.saved[0]))));
      },
      [alpha](auto v) { return (v > T(0)).select(v, alpha * (v.min(T(0)).exp() - T(1))); },
      {double(alpha)});
}

template <typename T>
Var<T> selu(const Var<T>& x) {
  // Constants of Klambauer et al. (2017), as in PyTorch.
  constexpr double kAlpha = 1.6732632423543772848170429916717;
  constexpr double kScale = 1.0507009873554804934193349852946;
  return scale(elu(x, static_cast<T>(kAlpha)), static_cast<T>(kScale));
}

template <typename T>
Var<T> swish(const Var<T>& x) {
  return x * sigmoid(x);
}

#define HNN_INSTANTIATE(T)                                     \
  template Var<T> add(const Var<T>&, const Var<T>&);           \
  template Var<T> sub(const Var<T>&, const Var<T>&);           \
  template Var<T> mul(const Var<T>&, const Var<T>&);           \
  template Var<T> div(const Var<T>&, const Var<T>&);           \
  template Var<T> neg(const Var<T>&);                          \
  template Var<T> scale(const Var<T>&, T);                     \
  template Var<T> shift(const Var<T>&, T);                     \
  template Var<T> square(const Var<T>&);                       \
  template Var<T> pow(const Var<T>&, T);                       \
  template Var<T> sqrt(const Var<T>&);                         \
  template Var<T> exp(const Var<T>&);                          \
  template Var<T> log(const Var<T>&);                          \
  template Var<T> sin(const Var<T>&);                          \
  template Var<T> cos(const Var<T>&);                          \
  template Var<T> tanh(const Var<T>&);                         \
  template Var<T> tanh_backward(const Var<T>&, const Var<T>&); \
  template Var<T> sigmoid(const Var<T>&);                      \
  template Var<T> step(const Var<T>&);                         \
  template Var<T> relu(const Var<T>&);                         \
  template Var<T> softplus(const Var<T>&);                     \
  template Var<T> elu(const Var<T>&, T);                       \
  template Var<T> selu(const Var<T>&);                         \
  template Var<T> swish(const Var<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
