#pragma once
// Reverse-mode differentiation: the sweep over the tape.

#include <vector>

#include "autodiff/var.h"

namespace hnn::ad {

struct GradOptions {
  bool create_graph = false;  // record the backward pass, so the result can be differentiated
  bool allow_unused = false;  // an input the outputs do not depend on gets zeros, not an error
};

/// d(sum_k <grad_outputs[k], outputs[k]>) / d inputs[j] for each j. Missing grad_outputs are
/// ones. With create_graph the results are on the tape and can be differentiated again, to any
/// order. Throws when an input does not require gradients or (without allow_unused) does not
/// reach the outputs.
template <typename T>
std::vector<Var<T>> grad(const std::vector<Var<T>>& outputs, const std::vector<Var<T>>& inputs,
                         const GradOptions& options = {},
                         const std::vector<Var<T>>& grad_outputs = {});

/// grad() of one output into `result` (resized; its storage reused): the allocation-free form
/// of a training loop's `grad({loss}, parameters)`, or, with grad_output, of
/// `grad({y}, inputs, options, {grad_output})`.
template <typename T>
void grad_into(const Var<T>& output, const std::vector<Var<T>>& inputs, std::vector<Var<T>>& result,
               const GradOptions& options = {}, const Var<T>& grad_output = {});

/// Accumulates d output / d leaf into every leaf's grad() that requires gradients (the output
/// must be 1x1 unless grad_output is given).
template <typename T>
void backward(const Var<T>& output, const Var<T>& grad_output = {});

}  // namespace hnn::ad
