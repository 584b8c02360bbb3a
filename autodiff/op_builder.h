#pragma once
// Internal: how an op records its result. Include only from the engine's .cpp files.

#include <initializer_list>
#include <span>

#include "autodiff/tape.h"

namespace hnn::ad::detail {

/// Pushes the result node of `op` on the tape. The node keeps its inputs and backward only when
/// grad mode is on and some input requires a gradient; the caller then fills `value` from its
/// own operands (never from node.inputs, which may be empty) and may attach typed state
/// (Node::state_for). Inputs are set here once: nothing reassigns them afterwards.
template <typename T>
Node<T>& record(const char* op, std::span<const Var<T>> inputs, BackwardFn<T> backward) {
  Node<T>& node = Tape<T>::current().push();
  node.op = op;
  if (!grad_enabled()) return node;
  bool any = false;
  for (const Var<T>& in : inputs) any = any || in.requires_grad();
  if (!any) return node;
  node.requires_grad = true;
  node.backward = backward;
  node.inputs.assign(inputs.begin(), inputs.end());
  return node;
}

template <typename T>
Node<T>& record(const char* op, std::initializer_list<Var<T>> inputs, BackwardFn<T> backward) {
  return record<T>(op, std::span<const Var<T>>(inputs.begin(), inputs.size()), backward);
}

}  // namespace hnn::ad::detail
