#include "autodiff/functional.h"

#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::ad {

namespace {

// One row of a Jacobian: the gradient of output element `index` of y with respect to x.
template <typename T>
Matrix<T> gradient_of_element(const Var<T>& y, const Var<T>& x, Eigen::Index index) {
  Matrix<T> seed = Matrix<T>::Zero(y.rows(), y.cols());
  seed.data()[index] = T(1);
  if (!y.requires_grad()) return Matrix<T>::Zero(1, x.rows() * x.cols());
  const Var<T> g = grad<T>({y}, {x}, GradOptions{.create_graph = false, .allow_unused = true},
                           {Var<T>::constant(seed)})[0];
  return g.value().template reshaped<Eigen::RowMajor>().transpose();
}

template <typename T>
Matrix<T> jacobian_of(const Var<T>& y, const Var<T>& x) {
  Matrix<T> jac(y.rows() * y.cols(), x.rows() * x.cols());
  for (Eigen::Index i = 0; i < jac.rows(); ++i) jac.row(i) = gradient_of_element(y, x, i);
  return jac;
}

// Ones in column `column` of a rows x cols tape node, zeros elsewhere: the seed of one reverse
// pass of row_jacobian, filled in place in a recycled node (no temporary matrix).
template <typename T>
Var<T> column_seed(Eigen::Index rows, Eigen::Index cols, Eigen::Index column) {
  Node<T>& node = Tape<T>::current().push();
  node.op = "row_jacobian_seed";
  node.value.setZero(rows, cols);
  node.value.col(column).setOnes();
  return Var<T>::of(node);
}

template <typename T>
Var<T> zeros(Eigen::Index rows, Eigen::Index cols) {
  Node<T>& node = Tape<T>::current().push();
  node.op = "zeros";
  node.value.setZero(rows, cols);
  return Var<T>::of(node);
}

}  // namespace

template <typename T>
Var<T> row_jacobian(const Var<T>& y, const Var<T>& x, const GradOptions& options) {
  HNN_AD_CHECK(y.rows() == x.rows(), "row_jacobian: y {} and x {} have different row counts",
               y.shape(), x.shape());
  HNN_AD_CHECK(y.cols() > 0, "row_jacobian: y {} has no columns", y.shape());
  if (!y.requires_grad() && options.allow_unused) return zeros<T>(x.rows(), y.cols() * x.cols());
  // Reused per thread, so a warmed-up training step allocates nothing; emptied before returning
  // so that no handle outlives the call. (No backward formula calls row_jacobian: no nesting.)
  thread_local std::vector<Var<T>> blocks, inputs, block;  // block j: d y[:, j] / d x, R x n
  blocks.clear();
  inputs.assign(1, x);
  for (Eigen::Index j = 0; j < y.cols(); ++j) {
    grad_into<T>(y, inputs, block, options, column_seed<T>(y.rows(), y.cols(), j));
    blocks.push_back(block[0]);
  }
  const Var<T> jacobian = concat_cols(blocks);
  blocks.clear();
  inputs.clear();
  block.clear();
  return jacobian;
}

template <typename T>
Var<T> row_hessian(const Var<T>& l, const Var<T>& x, const GradOptions& options) {
  HNN_AD_CHECK(l.cols() == 1 && l.rows() == x.rows(),
               "row_hessian: l must be one scalar per row of x {}, got {}", x.shape(), l.shape());
  thread_local std::vector<Var<T>> inputs, result;  // reused: no allocation per step
  inputs.assign(1, x);
  grad_into<T>(l, inputs, result,
               GradOptions{.create_graph = true, .allow_unused = options.allow_unused});
  const Var<T> gradient = result[0];
  inputs.clear();  // no handle outlives the call
  result.clear();
  // A gradient that is constant in x (l linear in x) has a zero Hessian, not an error.
  return row_jacobian(gradient, x,
                      GradOptions{.create_graph = options.create_graph, .allow_unused = true});
}

template <typename T>
Matrix<T> jacobian(const VarFunction<T>& f, const Matrix<T>& x) {
  TapeScope scope;
  const Var<T> xv = Var<T>::leaf(x);
  return jacobian_of(f(xv), xv);
}

template <typename T>
Matrix<T> hessian(const VarFunction<T>& f, const Matrix<T>& x) {
  TapeScope scope;
  const Var<T> xv = Var<T>::leaf(x);
  const Var<T> y = f(xv);
  HNN_AD_CHECK(y.rows() == 1 && y.cols() == 1, "hessian: f must be scalar, got {}", y.shape());
  const Var<T> g = grad<T>({y}, {xv}, GradOptions{.create_graph = true})[0];
  return jacobian_of(g, xv);
}

template <typename T>
Matrix<T> hvp(const VarFunction<T>& f, const Matrix<T>& x, const Matrix<T>& v) {
  HNN_AD_CHECK(v.rows() == x.rows() && v.cols() == x.cols(), "hvp: v is {} but x is {}",
               shape_str(v.rows(), v.cols()), shape_str(x.rows(), x.cols()));
  TapeScope scope;
  const Var<T> xv = Var<T>::leaf(x);
  const Var<T> y = f(xv);
  HNN_AD_CHECK(y.rows() == 1 && y.cols() == 1, "hvp: f must be scalar, got {}", y.shape());
  const Var<T> g = grad<T>({y}, {xv}, GradOptions{.create_graph = true})[0];
  if (!g.requires_grad()) return Matrix<T>::Zero(x.rows(), x.cols());
  return grad<T>({g}, {xv}, GradOptions{.allow_unused = true}, {Var<T>::constant(v)})[0].value();
}

#define HNN_INSTANTIATE(T)                                                           \
  template Matrix<T> jacobian(const VarFunction<T>&, const Matrix<T>&);              \
  template Matrix<T> hessian(const VarFunction<T>&, const Matrix<T>&);               \
  template Matrix<T> hvp(const VarFunction<T>&, const Matrix<T>&, const Matrix<T>&); \
  template Var<T> row_jacobian(const Var<T>&, const Var<T>&, const GradOptions&);    \
  template Var<T> row_hessian(const Var<T>&, const Var<T>&, const GradOptions&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
