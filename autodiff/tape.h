#pragma once
// The tape: the per-thread record of op results, in execution order. Nodes are recycled, not
// freed: a TapeScope rewinds the tape when it ends, and the next step reuses the same nodes, their
// value buffers and their typed op state (OpState, var.h), so a repeated training step allocates
// nothing in steady state.

#include <cstddef>
#include <memory>
#include <vector>

#include "autodiff/var.h"

namespace hnn::ad {

template <typename T>
class Tape {
 public:
  /// The calling thread's tape for scalar type T.
  static Tape& current();

  /// A fresh (recycled) node at the end of the tape.
  Node<T>& push();
  std::size_t size() const { return size_; }
  /// Nodes ever created: stays flat when steps are scoped (what the memory tests check).
  std::size_t capacity() const { return nodes_.size(); }
  /// Drops every node from `mark` on: their handles become stale, their buffers are kept.
  void rewind(std::size_t mark);
  /// Frees the buffers of recycled nodes too (memory back to the system).
  void release();

 private:
  std::vector<std::unique_ptr<Node<T>>> nodes_;
  std::size_t size_ = 0;
};

/// Everything recorded on the thread's tapes (float and double) while this scope lives is
/// released when it ends. Scopes nest.
class TapeScope {
 public:
  TapeScope();
  ~TapeScope();
  TapeScope(const TapeScope&) = delete;
  TapeScope& operator=(const TapeScope&) = delete;

 private:
  std::size_t float_mark_, double_mark_;
};

/// Whether ops record their backward (true unless a NoGradGuard is alive on this thread).
bool grad_enabled();

/// Sets the thread's grad mode for the scope's lifetime, restoring it afterwards.
class GradModeGuard {
 public:
  explicit GradModeGuard(bool enabled);
  ~GradModeGuard();
  GradModeGuard(const GradModeGuard&) = delete;
  GradModeGuard& operator=(const GradModeGuard&) = delete;

 private:
  bool previous_;
};

/// Ops inside this scope compute values only (rollouts, evaluation, optimiser updates).
class NoGradGuard : public GradModeGuard {
 public:
  NoGradGuard() : GradModeGuard(false) {}
};

}  // namespace hnn::ad
