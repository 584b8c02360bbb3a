// The fused tanh-MLP ops (mlp_ops.h): checks, recording, and the choice between the hand-written
// kernels (mlp_kernels.cpp) and the recorded formulas (mlp_recorded.cpp) for the backward.

#include "autodiff/mlp_layers.h"
#include "autodiff/mlp_ops.h"
#include "autodiff/op_builder.h"

namespace hnn::ad {

namespace {

using detail::MlpLayers;
using detail::MlpLayout;

// Throws unless the layers chain from x's width, with one bias entry (maybe undefined) each. The
// last bias is checked only when the op uses it (last_bias).
template <typename T>
void check_layers(const char* op, const Var<T>& x, const std::vector<Var<T>>& weights,
                  const std::vector<Var<T>>& biases, bool last_bias) {
  HNN_AD_CHECK(!weights.empty() && weights.size() == biases.size(),
               "{}: {} weights and {} biases (need at least one layer, one bias entry each)", op,
               weights.size(), biases.size());
  Eigen::Index width = x.cols();
  for (std::size_t i = 0; i < weights.size(); ++i) {
    HNN_AD_CHECK(weights[i].rows() == width,
                 "{}: layer {} weight is {} but its input has {} columns", op, i + 1,
                 weights[i].shape(), width);
    width = weights[i].cols();
    if (biases[i].defined() && (i + 1 < biases.size() || last_bias)) {
      HNN_AD_CHECK(biases[i].rows() == 1 && biases[i].cols() == width,
                   "{}: layer {} bias is {}, expected 1x{}", op, i + 1, biases[i].shape(), width);
    }
  }
}

// The node's inputs in MlpLayout's order, in a buffer reused across calls (no allocation).
template <typename T>
std::vector<Var<T>>& gather_inputs(const Var<T>& x, const std::vector<Var<T>>& weights,
                                   const MlpLayout& layout, const std::vector<Var<T>>& biases) {
  thread_local std::vector<Var<T>> inputs;
  inputs.assign(1, x);
  inputs.insert(inputs.end(), weights.begin(), weights.end());
  for (int k = 1; k <= layout.layers; ++k) {
    if (layout.bias_input[std::size_t(k - 1)] >= 0) inputs.push_back(biases[std::size_t(k - 1)]);
  }
  return inputs;
}

// Records a fused node with its layout and runs `forward` on it. The forward reads the caller's
// inputs, not the node's: a node that needs no gradient keeps none (op_builder.h).
template <typename T>
Var<T> record_fused(const char* op, const Var<T>& x, const std::vector<Var<T>>& weights,
                    const std::vector<Var<T>>& biases, bool last_bias, BackwardFn<T> backward,
                    void (*forward)(const MlpLayers<T>&, Node<T>&)) {
  // The layout decides the inputs, which record() needs before the node exists: it is built in
  // scratch first, then copied into the node's state.
  thread_local MlpLayout layout;
  layout.set(biases, last_bias);
  std::vector<Var<T>>& inputs = gather_inputs(x, weights, layout, biases);
  Node<T>& node = detail::record<T>(op, std::span<const Var<T>>(inputs), backward);
  MlpLayout& kept = node.template state_for<MlpLayout>();
  kept = layout;  // reuses the recycled state's storage
  forward(MlpLayers<T>{inputs, kept}, node);
  inputs.clear();  // release the parameters' handles (capacity stays)
  return Var<T>::of(node);
}

template <typename T>
void tanh_mlp_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  if (grad_enabled()) return detail::tanh_mlp_backward_recorded(detail::layers_of(n), g, s);
  detail::tanh_mlp_backward_kernel(n, g, s);
}

template <typename T>
void input_gradient_backward(const Node<T>& n, const Var<T>& g, GradSink<T>& s) {
  if (grad_enabled()) {
    return detail::input_gradient_backward_recorded(detail::layers_of(n), g, s);
  }
  detail::input_gradient_backward_kernel(n, g, s);
}

}  // namespace

template <typename T>
Var<T> tanh_mlp(const Var<T>& x, const std::vector<Var<T>>& weights,
                const std::vector<Var<T>>& biases) {
  check_layers("tanh_mlp", x, weights, biases, /*last_bias=*/true);
  return record_fused<T>("tanh_mlp", x, weights, biases, /*last_bias=*/true, tanh_mlp_backward<T>,
                         detail::tanh_mlp_forward<T>);
}

template <typename T>
Var<T> tanh_mlp_input_gradient(const Var<T>& x, const std::vector<Var<T>>& weights,
                               const std::vector<Var<T>>& biases) {
  check_layers("tanh_mlp_input_gradient", x, weights, biases, /*last_bias=*/false);
  // The last bias does not affect dy/dx: it is not an input.
  return record_fused<T>("tanh_mlp_input_gradient", x, weights, biases, /*last_bias=*/false,
                         input_gradient_backward<T>, detail::input_gradient_forward<T>);
}

#define HNN_INSTANTIATE(T)                                                                         \
  template Var<T> tanh_mlp(const Var<T>&, const std::vector<Var<T>>&, const std::vector<Var<T>>&); \
  template Var<T> tanh_mlp_input_gradient(const Var<T>&, const std::vector<Var<T>>&,               \
                                          const std::vector<Var<T>>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::ad
