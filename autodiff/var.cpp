#include "autodiff/var.h"

#include "autodiff/tape.h"

namespace hnn::ad {

template <typename T>
Var<T> Var<T>::leaf(Matrix<T> value, bool requires_grad) {
  auto node = std::make_shared<Node<T>>();
  node->value = std::move(value);
  node->op = "leaf";
  node->is_leaf = true;
  node->requires_grad = requires_grad;
  Node<T>* raw = node.get();
  return Var(raw, std::move(node));
}

template <typename T>
Var<T> Var<T>::constant(const MatrixView<T>& value) {
  Node<T>& node = Tape<T>::current().push();
  node.op = "constant";
  node.value = value;
  return of(node);
}

template <typename T>
Var<T> Var<T>::variable(const MatrixView<T>& value) {
  Node<T>& node = Tape<T>::current().push();
  node.op = "variable";
  node.value = value;
  node.requires_grad = true;
  return of(node);
}

template <typename T>
Matrix<T>& Var<T>::mutable_value() {
  HNN_AD_CHECK(is_leaf(), "autodiff: only a leaf's value can be changed in place, not op '{}'",
               op());
  return node().value;
}

template <typename T>
T Var<T>::item() const {
  HNN_AD_CHECK(rows() == 1 && cols() == 1, "item: expected a 1x1 value, got {} from op '{}'",
               shape(), op());
  return value()(0, 0);
}

template <typename T>
const Matrix<T>& Var<T>::grad() const {
  Node<T>& n = node();
  HNN_AD_CHECK(n.is_leaf, "grad: only leaves accumulate gradients (op '{}'); use ad::grad()", n.op);
  if (!n.has_grad) {
    n.grad.setZero(n.value.rows(), n.value.cols());
    n.has_grad = true;
  }
  return n.grad;
}

template <typename T>
void Var<T>::zero_grad() {
  Node<T>& n = node();
  n.grad.setZero(n.value.rows(), n.value.cols());
  n.has_grad = true;
}

template <typename T>
void Var<T>::set_requires_grad(bool on) {
  HNN_AD_CHECK(is_leaf(), "set_requires_grad: only leaves, not op '{}'", op());
  node().requires_grad = on;
}

template class Var<float>;
template class Var<double>;

}  // namespace hnn::ad
