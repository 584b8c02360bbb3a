#pragma once
// Training steps split by rows: each of the engine's threads takes a block of the batch's rows
// and computes that block's loss and gradients on its own tape, through its own replica of the
// model; the gradients are summed afterwards (Note [Rows, not ops] in row_split.cpp). Splitting
// every op instead costs a parallel region per op, and the worker waits while the caller runs
// the small ops alone.

#include <memory>
#include <vector>

#include "autodiff/parallel.h"
#include "autodiff/tape.h"
#include "autodiff/var.h"
#include "nn/dynamics.h"

namespace hnn::nn {

/// Below this many rows a part's products are too thin to keep a core busy: a batch of fewer
/// than twice this many is not split by rows.
inline constexpr Index kMinSplitRows = 64;

/// How many row blocks a batch of `rows` is split into at `threads` threads: one per thread, at
/// least kMinSplitRows rows each; 1 means "do not split".
int row_split_parts(Index rows, int threads);

template <typename T>
class RowSplit {
 public:
  /// Replicas of `model` for parts 1 .. parts - 1 (part 0 computes with `model` itself). The
  /// model must outlive this object; its parameters are copied into the replicas every step.
  RowSplit(const DynamicsModel<T>& model, int parts);

  int parts() const { return parts_; }

  /// One step's mean loss over `rows` rows and its gradients with respect to the model's
  /// parameters (in parameters() order) into `grads`, leaves owned here and reused from step to
  /// step. `loss(model, block)` gives the mean loss of rows `block` computed by `model`, the
  /// part's replica (it runs on any thread, concurrently with the other parts). The blocks are
  /// ad::row_block(rows, parts(), part); each part's loss weighs by its share of the rows. The
  /// result depends only on parts(), not on which thread ran which part.
  template <typename LossFn>
  double loss_and_gradients(Index rows, const LossFn& loss, std::vector<ad::Var<T>>& grads) {
    const auto part = [&](int p) {
      const ad::RowBlock block = ad::row_block(rows, parts_, p);
      sync(p);
      ad::TapeScope scope;  // the part's graph lives on the thread that runs it
      keep(p, block.size(), rows, loss(member(p), block));
    };
    // Each thread its own part every step, so that its tape keeps the part's shapes.
    if (parts_ <= ad::num_threads()) {
      ad::parallel_for_each_thread(parts_, part);
    } else {
      ad::parallel_for(parts_, part);
    }
    return sum_into(grads);
  }

 private:
  const DynamicsModel<T>& member(int p) const { return p == 0 ? model_ : *replicas_[p - 1]; }
  // Part p's replica takes the model's current parameter values.
  void sync(int p);
  // Part p's loss and its gradients, weighed by rows / total, into the part's own buffers.
  void keep(int p, Index rows, Index total, const ad::Var<T>& loss);
  // The parts' weighed losses and gradients summed, in part order.
  double sum_into(std::vector<ad::Var<T>>& grads);

  const DynamicsModel<T>& model_;
  int parts_;
  std::vector<std::unique_ptr<DynamicsModel<T>>> replicas_;
  // Per part: its model's parameters, its gradient handles, its weighed gradients and loss.
  std::vector<std::vector<ad::Var<T>>> params_, part_grads_;
  std::vector<std::vector<Matrix<T>>> weighed_;
  std::vector<double> losses_;
  std::vector<ad::Var<T>> sums_;  // the summed gradients: leaves, so a step allocates nothing
};

}  // namespace hnn::nn
