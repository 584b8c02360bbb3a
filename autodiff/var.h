#pragma once
// Var: the handle of the engine. A Var names a Node holding a 2-D value (rows = batch,
// cols = features). Leaves (parameters, inputs) own their node and persist; every op result is
// a node on the thread's tape, recycled when the enclosing TapeScope ends.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "autodiff/check.h"

namespace hnn::ad {

template <typename T>
using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

template <typename T>
class Var;
template <typename T>
struct Node;
template <typename T>
class GradSink;

/// Vector-Jacobian product of one node: given the gradient of its output, add the gradient of
/// each input to `sink`, written with differentiable ops so it can be recorded (higher order).
template <typename T>
using BackwardFn = void (*)(const Node<T>& node, const Var<T>& grad_output, GradSink<T>& sink);

template <typename T>
struct Node {
  Matrix<T> value;
  std::vector<Var<T>> inputs;         // capacity kept across recycling: no allocation per step
  BackwardFn<T> backward = nullptr;   // null for leaves and for results that need no gradient
  std::array<double, 3> saved{};      // op constants (exponent, offsets, ...)
  std::vector<Matrix<T>> buffers;     // fused ops' saved intermediates; kept across recycling
  const char* op = "leaf";
  bool requires_grad = false;
  bool is_leaf = false;
  std::uint32_t generation = 0;       // bumped when a tape slot is reused: detects stale handles
  std::uint64_t seq = 0;              // creation order = a topological order of the graph
  // Bookkeeping of the gradient sweep that last visited this node.
  std::uint64_t sweep = 0;
  int slot = -1;
  Matrix<T> grad;                     // accumulated by backward(), leaves only
  bool has_grad = false;
};

template <typename T>
class Var {
 public:
  Var() = default;

  /// A persistent leaf (a parameter or an input to differentiate with respect to).
  static Var leaf(Matrix<T> value, bool requires_grad = true);
  /// A scratch constant on the tape: no gradient, buffer recycled with the tape.
  static Var constant(const Matrix<T>& value);
  /// Wraps a node that is on the tape (used by backward formulas to refer to outputs).
  static Var of(const Node<T>& node) { return Var(const_cast<Node<T>*>(&node), nullptr); }

  bool defined() const { return node_ != nullptr; }
  const Matrix<T>& value() const { return node().value; }
  /// Mutable access for leaves only (optimisers update parameters in place).
  Matrix<T>& mutable_value();
  Eigen::Index rows() const { return node().value.rows(); }
  Eigen::Index cols() const { return node().value.cols(); }
  std::string shape() const { return shape_str(rows(), cols()); }
  /// The single value of a 1x1 Var.
  T item() const;
  bool requires_grad() const { return node().requires_grad; }
  bool is_leaf() const { return node().is_leaf; }
  const char* op() const { return node().op; }

  /// Gradient accumulated by backward() into a leaf (zeros before any backward).
  const Matrix<T>& grad() const;
  bool has_grad() const { return node().has_grad; }
  void zero_grad();
  void set_requires_grad(bool on);

  /// The node this handle names; throws when the TapeScope that created it has ended.
  Node<T>& node() const {
    HNN_AD_CHECK(node_ != nullptr, "autodiff: use of an empty Var");
    HNN_AD_CHECK(node_->generation == generation_,
                 "autodiff: Var of op '{}' used after its TapeScope ended (its tape slot was "
                 "recycled); keep results as Matrix values or as leaves",
                 node_->op);
    return *node_;
  }

 private:
  Var(Node<T>* node, std::shared_ptr<Node<T>> owner)
      : node_(node), generation_(node->generation), owner_(std::move(owner)) {}

  Node<T>* node_ = nullptr;
  std::uint32_t generation_ = 0;
  std::shared_ptr<Node<T>> owner_;  // set for leaves, which live outside the tape
};

/// The sink a BackwardFn writes input gradients into.
template <typename T>
class GradSink {
 public:
  virtual ~GradSink() = default;
  /// True when the gradient of input `i` is needed by this sweep (skip work otherwise).
  virtual bool wants(int i) const = 0;
  virtual void add(int i, const Var<T>& grad) = 0;
};

}  // namespace hnn::ad
