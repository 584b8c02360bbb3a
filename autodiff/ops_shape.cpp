// Reductions, broadcasting, column slicing and reshaping: the ops that change shapes.

#include "autodiff/op_builder.h"
#include "autodiff/ops.h"
#include "autodiff/row_kernels.h"

namespace hnn::ad {

namespace {

template <typename T>
const Var<T>& in0(const Node<T>& n) {
  return n.inputs[0];
}

// Gradient of every reduction: the incoming gradient broadcast back (times a mean's 1/count). A
// mean's factor scales the reduced gradient before it spreads, the same products on far fewer
// elements (a 200 x 1568 pass fewer per pixel-task step).
template <typename T>
void reduce_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  const Var<T>& x = in0(n);
  const T factor = static_cast<T>(n.saved[0]);
  s.add(0, broadcast_to(factor == T(1) ? g : scale(g, factor), x.rows(), x.cols()));
}

// value = reduce(x), with the gradient factor (1 for sums, 1/count for means).
template <typename T, typename F>
Var<T> reduction(const char* op, const Var<T>& x, double factor, F reduce) {
  Node<T>& node = detail::record<T>(op, {x}, reduce_backward<T>);
  node.saved[0] = factor;
  reduce(x.value(), node.value);
  if (factor != 1.0) node.value *= static_cast<T>(factor);
  return Var<T>::of(node);
}

template <typename T>
void sum_all(const Matrix<T>& x, Matrix<T>& out) {
  out.resize(1, 1);
  out(0, 0) = x.sum();
}
template <typename T>
void sum_over_rows(const Matrix<T>& x, Matrix<T>& out) {
  out.resize(1, x.cols());
  detail::column_sums(x, out);
}
template <typename T>
void sum_over_cols(const Matrix<T>& x, Matrix<T>& out) {
  out.noalias() = x.rowwise().sum();
}

}  // namespace

template <typename T>
Var<T> sum(const Var<T>& a) {
  return reduction<T>("sum", a, 1.0, sum_all<T>);
}
template <typename T>
Var<T> mean(const Var<T>& a) {
  HNN_AD_CHECK(a.rows() * a.cols() > 0, "mean: empty input {}", a.shape());
  return reduction<T>("mean", a, 1.0 / double(a.rows() * a.cols()), sum_all<T>);
}
template <typename T>
Var<T> sum_rows(const Var<T>& a) {
  return reduction<T>("sum_rows", a, 1.0, sum_over_rows<T>);
}
template <typename T>
Var<T> sum_cols(const Var<T>& a) {
  return reduction<T>("sum_cols", a, 1.0, sum_over_cols<T>);
}
template <typename T>
Var<T> mean_rows(const Var<T>& a) {
  HNN_AD_CHECK(a.rows() > 0, "mean_rows: empty input {}", a.shape());
  return reduction<T>("mean_rows", a, 1.0 / double(a.rows()), sum_over_rows<T>);
}
template <typename T>
Var<T> mean_cols(const Var<T>& a) {
  HNN_AD_CHECK(a.cols() > 0, "mean_cols: empty input {}", a.shape());
  return reduction<T>("mean_cols", a, 1.0 / double(a.cols()), sum_over_cols<T>);
}

template <typename T>
Var<T> broadcast_to(const Var<T>& a, Eigen::Index rows, Eigen::Index cols) {
  HNN_AD_CHECK((a.rows() == rows || a.rows() == 1) && (a.cols() == cols || a.cols() == 1),
               "broadcast_to: cannot broadcast {} to {}", a.shape(), shape_str(rows, cols));
  if (a.rows() == rows && a.cols() == cols) return a;
  Node<T>& node =
      detail::record<T>("broadcast_to", {a}, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, sum_to(g, in0(n).rows(), in0(n).cols()));
      });
  // Each dimension is a's or 1, so a is a scalar, a row (a bias) or a column (a row reduction's
  // gradient): each by vectorised fills. Eigen's replicate() indexed every element by a modulo.
  node.value.resize(rows, cols);
  if (a.value().size() == 1) {
    node.value.setConstant(a.value()(0, 0));
  } else if (a.rows() == 1) {
    detail::fill_rows(node.value, a.value().row(0));
  } else {
    for (Eigen::Index i = 0; i < rows; ++i) node.value.row(i).setConstant(a.value()(i, 0));
  }
  return Var<T>::of(node);
}

template <typename T>
Var<T> sum_to(const Var<T>& a, Eigen::Index rows, Eigen::Index cols) {
  HNN_AD_CHECK((rows == a.rows() || rows == 1) && (cols == a.cols() || cols == 1),
               "sum_to: cannot sum {} to {}", a.shape(), shape_str(rows, cols));
  const bool keep_rows = rows == a.rows(), keep_cols = cols == a.cols();
  if (keep_rows && keep_cols) return a;
  if (!keep_rows && !keep_cols) return sum(a);
  return keep_cols ? sum_rows(a) : sum_cols(a);
}

template <typename T>
Var<T> slice_cols(const Var<T>& a, Eigen::Index start, Eigen::Index count) {
  HNN_AD_CHECK(start >= 0 && count >= 0 && start + count <= a.cols(),
               "slice_cols: columns [{}, {}) out of range for {}", start, start + count, a.shape());
  Node<T>& node =
      detail::record<T>("slice_cols", {a}, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, pad_cols(g, static_cast<Eigen::Index>(n.saved[0]), in0(n).cols()));
      });
  node.saved[0] = double(start);
  node.value.resize(a.rows(), count);
  detail::copy_cols(a.value(), start, node.value, 0, count);
  return Var<T>::of(node);
}

template <typename T>
Var<T> pad_cols(const Var<T>& a, Eigen::Index start, Eigen::Index cols) {
  HNN_AD_CHECK(start >= 0 && start + a.cols() <= cols,
               "pad_cols: {} does not fit at column {} of {} columns", a.shape(), start, cols);
  Node<T>& node =
      detail::record<T>("pad_cols", {a}, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, slice_cols(g, static_cast<Eigen::Index>(n.saved[0]), in0(n).cols()));
      });
  node.saved[0] = double(start);
  node.value.setZero(a.rows(), cols);
  detail::copy_cols(a.value(), 0, node.value, start, a.cols());
  return Var<T>::of(node);
}

template <typename T>
Var<T> reshape(const Var<T>& a, Eigen::Index rows, Eigen::Index cols) {
  HNN_AD_CHECK(rows >= 0 && cols >= 0 && rows * cols == a.rows() * a.cols(),
               "reshape: cannot reshape {} to {}", a.shape(), shape_str(rows, cols));
  if (a.rows() == rows && a.cols() == cols) return a;
  Node<T>& node =
      detail::record<T>("reshape", {a}, [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
        s.add(0, reshape(g, in0(n).rows(), in0(n).cols()));
      });
  node.value = a.value().reshaped(rows, cols);
  return Var<T>::of(node);
}

namespace {

template <typename T>
Var<T> concat_span(std::span<const Var<T>> parts) {
  HNN_AD_CHECK(!parts.empty(), "concat_cols: no inputs");
  Eigen::Index cols = 0;
  for (const Var<T>& p : parts) {
    HNN_AD_CHECK(p.rows() == parts[0].rows(), "concat_cols: row counts differ: {} and {}",
                 parts[0].shape(), p.shape());
    cols += p.cols();
  }
  Node<T>& node = detail::record<T>("concat_cols", parts,
                                    [](const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
                                      Eigen::Index start = 0;
                                      for (int i = 0; i < int(n.inputs.size()); ++i) {
                                        const Eigen::Index width = n.inputs[i].cols();
                                        if (s.wants(i)) s.add(i, slice_cols(g, start, width));
                                        start += width;
                                      }
                                    });
  node.value.resize(parts[0].rows(), cols);
  Eigen::Index start = 0;
  for (const Var<T>& p : parts) {
    detail::copy_cols(p.value(), 0, node.value, start, p.cols());
    start += p.cols();
  }
  return Var<T>::of(node);
}

}  // namespace

template <typename T>
Var<T> concat_cols(const std::vector<Var<T>>& parts) {
  return concat_span<T>(parts);
}

template <typename T>
Var<T> concat_cols(std::initializer_list<Var<T>> parts) {
  return concat_span<T>(std::span<const Var<T>>(parts.begin(), parts.size()));
}

#define HNN_INSTANTIATE(T)                                                 \
  template Var<T> sum(const Var<T>&);                                      \
  template Var<T> mean(const Var<T>&);                                     \
  template Var<T> sum_rows(const Var<T>&);                                 \
  template Var<T> sum_cols(const Var<T>&);                                 \
  template Var<T> mean_rows(const Var<T>&);                                \
  template Var<T> mean_cols(const Var<T>&);                                \
  template Var<T> broadcast_to(const Var<T>&, Eigen::Index, Eigen::Index); \
  template Var<T> sum_to(const Var<T>&, Eigen::Index, Eigen::Index);       \
  template Var<T> slice_cols(const Var<T>&, Eigen::Index, Eigen::Index);   \
  template Var<T> pad_cols(const Var<T>&, Eigen::Index, Eigen::Index);     \
  template Var<T> reshape(const Var<T>&, Eigen::Index, Eigen::Index);      \
  template Var<T> concat_cols(const std::vector<Var<T>>&);                 \
  template Var<T> concat_cols(std::initializer_list<Var<T>>);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
