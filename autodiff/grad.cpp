#include "autodiff/grad.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <span>
#include <utility>

#include "autodiff/ops.h"
#include "autodiff/parallel.h"
#include "autodiff/row_kernels.h"
#include "autodiff/tape.h"

namespace hnn::ad {
namespace ad = ::hnn::ad;

namespace {

// One counter for every thread: a node keeps the id of the last sweep that visited it, and leaves
// are reached from several threads (an LNN's rollouts sweep through the same parameters on every
// engine thread), so an id one thread hands out must never be another's too.
std::atomic<std::uint64_t> g_sweep_id{0};

// A sweep's working lists, kept per thread so that repeated sweeps allocate nothing. Sweeps can
// nest (a backward formula may call grad), hence a stack of them.
template <typename T>
struct SweepBuffers {
  std::vector<Node<T>*> order, leaves, targets;
  std::vector<Var<T>> grads;
  std::vector<char> owned;  // per slot: its gradient is a sum node only this sweep holds
  std::vector<std::pair<Node<T>*, std::size_t>> stack;
};

template <typename T>
class BorrowedBuffers {
 public:
  BorrowedBuffers() {
    if (depth() == pool().size()) pool().push_back(std::make_unique<SweepBuffers<T>>());
    buffers_ = pool()[depth()++].get();
  }
  ~BorrowedBuffers() {
    buffers_->grads.clear();  // drop references to nodes (capacity stays)
    --depth();
  }
  SweepBuffers<T>& operator*() { return *buffers_; }

 private:
  static std::vector<std::unique_ptr<SweepBuffers<T>>>& pool() {
    thread_local std::vector<std::unique_ptr<SweepBuffers<T>>> buffers;
    return buffers;
  }
  static std::size_t& depth() {
    thread_local std::size_t in_use = 0;
    return in_use;
  }
  SweepBuffers<T>* buffers_;
};

// sum += g, split over the engine's threads when big (each element the same addition).
template <typename T>
void add_in_place(Matrix<T>& sum, const Matrix<T>& g) {
  for_element_blocks(sum.size(), [&](RowBlock e) { detail::flat(sum, e) += detail::flat(g, e); });
}

// One reverse sweep: finds the nodes between the outputs and the targets, then propagates
// gradients through them in reverse creation order (a reverse topological order).
template <typename T>
class Sweep : public GradSink<T> {
 public:
  // targets: the nodes whose gradients are wanted; all_leaves: every leaf is a target.
  Sweep(SweepBuffers<T>& buffers, bool all_leaves)
      : id_(g_sweep_id.fetch_add(1, std::memory_order_relaxed) + 1),
        targets_(buffers.targets),
        all_leaves_(all_leaves),
        order_(buffers.order),
        leaves_(buffers.leaves),
        grads_(buffers.grads),
        owned_(buffers.owned),
        stack_(buffers.stack) {
    order_.clear();
    leaves_.clear();
    grads_.clear();
  }

  void run(std::span<const Var<T>> outputs, std::span<const Var<T>> grad_outputs,
           bool create_graph) {
    for (const Var<T>& out : outputs) visit(&out.node());
    std::sort(order_.begin(), order_.end(),
              [](const Node<T>* a, const Node<T>* b) { return a->seq > b->seq; });
    grads_.resize(slots_);
    owned_.assign(std::size_t(slots_), 0);
    GradModeGuard mode(create_graph);
    for (std::size_t k = 0; k < outputs.size(); ++k) {
      Node<T>& out = outputs[k].node();
      if (out.slot < 0) continue;
      const bool given = k < grad_outputs.size() && grad_outputs[k].defined();
      if (given) {
        HNN_AD_CHECK(grad_outputs[k].rows() == out.value.rows() &&
                         grad_outputs[k].cols() == out.value.cols(),
                     "grad: grad_outputs[{}] is {} but output {} is {}", k, grad_outputs[k].shape(),
                     k, shape_str(out.value.rows(), out.value.cols()));
      }
      accumulate(out.slot, given ? grad_outputs[k] : ones(out.value.rows(), out.value.cols()));
    }
    for (Node<T>* node : order_) {
      if (!grads_[node->slot].defined()) continue;
      current_ = node;
      // A target none of whose inputs is needed (grad with respect to an intermediate result)
      // has nothing to pass on.
      bool feeds_needed = false;
      for (int i = 0; i < int(node->inputs.size()); ++i) feeds_needed = feeds_needed || wants(i);
      if (feeds_needed) node->backward(*node, grads_[node->slot], *this);
    }
  }

  // The default seed, filled in place in a recycled tape node (no temporary matrix).
  static Var<T> ones(Eigen::Index rows, Eigen::Index cols) {
    Node<T>& node = Tape<T>::current().push();
    node.op = "ones";
    node.value.setOnes(rows, cols);
    return Var<T>::of(node);
  }

  /// The gradient reaching `node` (undefined when none does).
  Var<T> result(const Node<T>& node) const {
    return node.sweep == id_ && node.slot >= 0 ? grads_[node.slot] : Var<T>();
  }

  /// The leaves that received a slot (reached and needed).
  const std::vector<Node<T>*>& leaves() const { return leaves_; }

  bool wants(int i) const override {
    const Node<T>& in = current_->inputs[i].node();
    return in.requires_grad && in.sweep == id_ && in.slot >= 0;
  }

  void add(int i, const Var<T>& g) override {
    const Node<T>& in = current_->inputs[i].node();
    HNN_AD_CHECK(g.rows() == in.value.rows() && g.cols() == in.value.cols(),
                 "grad: backward of op '{}' gave a {} gradient for its input #{} of shape {}",
                 current_->op, g.shape(), i, shape_str(in.value.rows(), in.value.cols()));
    // Backward formulas may skip wants(): gradients of inputs this sweep does not need (slot -1
    // or a stale slot of an earlier sweep) are dropped here.
    if (!wants(i)) return;
    accumulate(in.slot, g);
  }

  // Note [Sums added into in place]: a weight that a rollout's 16 field evaluations reach got,
  // from each, a fresh product zeroed by the GEMM and then added into the sum here, two passes
  // over the weight's size per evaluation; the fused MLP kernels add their products into the sum
  // itself instead.
  Matrix<T>* sum_into(int i) override {
    if (grad_enabled() || !wants(i)) return nullptr;
    const Node<T>& in = current_->inputs[i].node();
    Var<T>& acc = grads_[in.slot];
    if (!owned_[in.slot]) {
      Node<T>& sum = Tape<T>::current().push();
      sum.op = "grad_sum";
      if (acc.defined()) {
        sum.value = acc.value();
      } else {
        sum.value.setZero(in.value.rows(), in.value.cols());
      }
      acc = Var<T>::of(sum);
      owned_[in.slot] = 1;
    }
    return &acc.node().value;
  }

 private:
  bool is_target(const Node<T>* node) const {
    if (all_leaves_ && node->is_leaf) return true;
    return std::find(targets_.begin(), targets_.end(), node) != targets_.end();
  }

  // Iterative post-order DFS over nodes that require gradients. A node gets a slot (is
  // "needed") when it is a target or some input of it is needed.
  void visit(Node<T>* root) {
    if (!root->requires_grad || root->sweep == id_) return;
    std::vector<std::pair<Node<T>*, std::size_t>>& stack = stack_;
    stack.clear();
    root->sweep = id_;
    root->slot = -1;
    stack.push_back({root, 0});
    while (!stack.empty()) {
      Node<T>* node = stack.back().first;
      const std::size_t next = stack.back().second++;
      if (next < node->inputs.size()) {
        Node<T>* child = &node->inputs[next].node();
        if (child->requires_grad && child->sweep != id_) {
          child->sweep = id_;
          child->slot = -1;
          stack.push_back({child, 0});
        }
        continue;
      }
      stack.pop_back();
      bool needed = is_target(node);
      for (const Var<T>& in : node->inputs) {
        const Node<T>& child = in.node();
        needed = needed || (child.sweep == id_ && child.slot >= 0);
      }
      if (!needed) continue;
      node->slot = slots_++;
      (node->is_leaf ? leaves_ : order_).push_back(node);
    }
  }

  // Sums a gradient into its slot. Without a recorded graph, a slot's second contribution makes
  // a sum node that only this sweep holds, and later ones are added into it in place: a weight
  // that a rollout's 16 field evaluations reach got 15 new nodes, each a pass over three
  // matrices. (A node's own slot is final before its backward hands the sum on, so the in-place
  // adds never touch a value someone else holds.)
  void accumulate(int slot, const Var<T>& g) {
    Var<T>& acc = grads_[slot];
    if (!acc.defined()) {
      acc = g;
    } else if (owned_[slot] && !grad_enabled()) {
      add_in_place(acc.node().value, g.value());
    } else {
      acc = ad::add(acc, g);
      owned_[slot] = !grad_enabled();
    }
  }

  std::uint64_t id_;
  const std::vector<Node<T>*>& targets_;
  bool all_leaves_;
  std::vector<Node<T>*>& order_;  // needed non-leaf nodes
  std::vector<Node<T>*>& leaves_;
  std::vector<Var<T>>& grads_;
  std::vector<char>& owned_;
  std::vector<std::pair<Node<T>*, std::size_t>>& stack_;
  int slots_ = 0;
  Node<T>* current_ = nullptr;
};

template <typename T>
std::string describe(const char* role, std::size_t index, const Var<T>& v) {
  return fmt::format("{} #{} ({} {})", role, index, v.shape(), v.op());
}

template <typename T>
void grad_impl(std::span<const Var<T>> outputs, const std::vector<Var<T>>& inputs,
               const GradOptions& options, std::span<const Var<T>> grad_outputs,
               std::vector<Var<T>>& result) {
  HNN_AD_CHECK(!outputs.empty(), "grad: no outputs given");
  HNN_AD_CHECK(grad_outputs.empty() || grad_outputs.size() == outputs.size(),
               "grad: {} grad_outputs for {} outputs", grad_outputs.size(), outputs.size());
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    HNN_AD_CHECK(outputs[k].requires_grad(),
                 "grad: {} does not require gradients: it was computed from constants only or "
                 "under a NoGradGuard",
                 describe("output", k, outputs[k]));
  }
  BorrowedBuffers<T> buffers;
  (*buffers).targets.clear();
  for (std::size_t j = 0; j < inputs.size(); ++j) {
    HNN_AD_CHECK(inputs[j].requires_grad(),
                 "grad: {} does not require gradients; create it with "
                 "Var::leaf(value, /*requires_grad=*/true)",
                 describe("input", j, inputs[j]));
    (*buffers).targets.push_back(&inputs[j].node());
  }
  Sweep<T> sweep(*buffers, /*all_leaves=*/false);
  sweep.run(outputs, grad_outputs, options.create_graph);

  result.resize(inputs.size());
  for (std::size_t j = 0; j < inputs.size(); ++j) {
    Var<T> g = sweep.result(inputs[j].node());
    if (!g.defined()) {
      HNN_AD_CHECK(options.allow_unused,
                   "grad: {} is not used to compute the outputs; pass allow_unused to get zeros",
                   describe("input", j, inputs[j]));
      g = Var<T>::constant(Matrix<T>::Zero(inputs[j].rows(), inputs[j].cols()));
    }
    result[j] = g;
  }
}

}  // namespace

template <typename T>
std::vector<Var<T>> grad(const std::vector<Var<T>>& outputs, const std::vector<Var<T>>& inputs,
                         const GradOptions& options, const std::vector<Var<T>>& grad_outputs) {
  std::vector<Var<T>> result;
  grad_impl<T>(outputs, inputs, options, grad_outputs, result);
  return result;
}

template <typename T>
void grad_into(const Var<T>& output, const std::vector<Var<T>>& inputs, std::vector<Var<T>>& result,
               const GradOptions& options, const Var<T>& grad_output) {
  const std::span<const Var<T>> seed =
      grad_output.defined() ? std::span<const Var<T>>(&grad_output, 1) : std::span<const Var<T>>();
  grad_impl<T>(std::span<const Var<T>>(&output, 1), inputs, options, seed, result);
}

template <typename T>
void backward(const Var<T>& output, const Var<T>& grad_output) {
  HNN_AD_CHECK(grad_output.defined() || (output.rows() == 1 && output.cols() == 1),
               "backward: output is {}; give grad_output for a non-scalar output", output.shape());
  HNN_AD_CHECK(output.requires_grad(),
               "backward: the output does not require gradients: it was computed from constants "
               "only or under a NoGradGuard");
  BorrowedBuffers<T> buffers;
  (*buffers).targets.clear();
  Sweep<T> sweep(*buffers, /*all_leaves=*/true);
  sweep.run(
      std::span<const Var<T>>(&output, 1),
      grad_output.defined() ? std::span<const Var<T>>(&grad_output, 1) : std::span<const Var<T>>(),
      /*create_graph=*/false);
  for (Node<T>* leaf : sweep.leaves()) {
    const Var<T> g = sweep.result(*leaf);
    if (!g.defined()) continue;
    if (!leaf->has_grad) leaf->grad.setZero(leaf->value.rows(), leaf->value.cols());
    leaf->grad += g.value();
    leaf->has_grad = true;
  }
}

template std::vector<Var<float>> grad(const std::vector<Var<float>>&,
                                      const std::vector<Var<float>>&, const GradOptions&,
                                      const std::vector<Var<float>>&);
template std::vector<Var<double>> grad(const std::vector<Var<double>>&,
                                       const std::vector<Var<double>>&, const GradOptions&,
                                       const std::vector<Var<double>>&);
template void grad_into(const Var<float>&, const std::vector<Var<float>>&, std::vector<Var<float>>&,
                        const GradOptions&, const Var<float>&);
template void grad_into(const Var<double>&, const std::vector<Var<double>>&,
                        std::vector<Var<double>>&, const GradOptions&, const Var<double>&);
template void backward(const Var<float>&, const Var<float>&);
template void backward(const Var<double>&, const Var<double>&);

}  // namespace hnn::ad
