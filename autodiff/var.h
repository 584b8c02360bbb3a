#pragma once
// Var: the handle of the engine. A Var names a Node holding a 2-D value (rows = batch,
// cols = features). Leaves (parameters, inputs) own their node and persist; every op result is
// a node on the thread's tape, recycled when the enclosing TapeScope ends.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <typeinfo>
#include <vector>

#include "autodiff/check.h"

namespace hnn::ad {

template <typename T>
using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// A read-only view of a Matrix<T> or of rows of memory laid out like one (a C-contiguous NumPy
/// array's buffer): what the entry points that only read their input take, so that a caller's
/// buffer reaches them without a copy.
template <typename T>
using MatrixView = Eigen::Ref<const Matrix<T>>;

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

/// State an op keeps on its node beyond values: a fused op's layer layout, say. Each op derives
/// its own struct with typed fields. A node keeps its state object when it is recycled, so the
/// same op in the same tape slot next step reuses it (and its vectors' capacity): no allocation
/// in a steady-state training step. See Node::state_for.
struct OpState {
  virtual ~OpState() = default;
};

template <typename T>
struct Node {
  Matrix<T> value;
  std::vector<Var<T>> inputs;        // capacity kept across recycling: no allocation per step
  BackwardFn<T> backward = nullptr;  // null for leaves and for results that need no gradient
  std::array<double, 3> saved{};     // op constants (exponent, offsets, ...)
  std::vector<Matrix<T>> buffers;    // fused ops' saved intermediates; kept across recycling
  std::unique_ptr<OpState> state;    // typed op state (see OpState); kept across recycling
  const char* op = "leaf";
  bool requires_grad = false;
  bool is_leaf = false;
  std::uint32_t generation = 0;  // bumped when a tape slot is reused: detects stale handles
  std::uint64_t seq = 0;         // creation order = a topological order of the graph
  // Bookkeeping of the gradient sweep that last visited this node.
  std::uint64_t sweep = 0;
  int slot = -1;
  Matrix<T> grad;  // accumulated by backward(), leaves only
  bool has_grad = false;

  /// The state of the op recording this node, as S: the recycled object when the slot already
  /// holds an S (its fields keep their old values: the op overwrites them), a new one otherwise.
  template <typename S>
  S& state_for() {
    static_assert(std::is_base_of_v<OpState, S>);
    if (!holds_state<S>()) state = std::make_unique<S>();
    return static_cast<S&>(*state);
  }
  /// The state a backward formula reads: the S its op stored with state_for<S>().
  template <typename S>
  const S& state_as() const {
    HNN_AD_CHECK(holds_state<S>(), "autodiff: node of op '{}' holds no {}", op, typeid(S).name());
    return static_cast<const S&>(*state);
  }
  /// Whether the node's state is an S.
  template <typename S>
  bool holds_state() const {
    if (!state) return false;
    const OpState& held = *state;
    return typeid(held) == typeid(S);
  }
};

template <typename T>
class Var {
 public:
  Var() = default;

  /// A persistent leaf (a parameter or an input to differentiate with respect to).
  static Var leaf(Matrix<T> value, bool requires_grad = true);
  /// A scratch constant on the tape: no gradient, buffer recycled with the tape.
  static Var constant(const MatrixView<T>& value);
  /// A scratch variable on the tape: a constant() that requires gradients, so grad() can
  /// differentiate with respect to it (a batch of states a field is differentiated in). Recycled
  /// with the tape, so a warmed-up step allocates nothing, unlike a leaf(). Not a leaf:
  /// backward() accumulates nothing into it.
  static Var variable(const MatrixView<T>& value);
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
  /// The sum of input i's gradient so far (zeros when none yet), for a backward to add its
  /// contribution into in place (a weight gradient's GEMM with beta = 1), or null when it must call
  /// add: the sweep records its backward, or does not want input i. A matrix given stays the
  /// input's gradient sum; later adds go into it.
  virtual Matrix<T>* sum_into(int /*i*/) { return nullptr; }
};

}  // namespace hnn::ad
