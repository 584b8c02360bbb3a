#include "nn/activation.h"

#include <fmt/format.h>

#include <array>
#include <stdexcept>
#include <string>

#include "autodiff/ops.h"
#include "nn/enum_names.h"

namespace hnn::nn {

namespace {
constexpr NameTable<Activation, 7> kActivationNames{{
    {Activation::kTanh, "tanh"},
    {Activation::kRelu, "relu"},
    {Activation::kSigmoid, "sigmoid"},
    {Activation::kSoftplus, "softplus"},
    {Activation::kElu, "elu"},
    {Activation::kSelu, "selu"},
    {Activation::kSwish, "swish"},
}};
}  // namespace

std::string_view to_string(Activation activation) { return name_of(kActivationNames, activation); }

Activation parse_activation(std::string_view name) {
  return parse_name(kActivationNames, name, "activation");
}

template <typename T>
ad::Var<T> activate(Activation activation, const ad::Var<T>& x) {
  switch (activation) {
    case Activation::kTanh:
      return ad::tanh(x);
    case Activation::kRelu:
      return ad::relu(x);
    case Activation::kSigmoid:
      return ad::sigmoid(x);
    case Activation::kSoftplus:
      return ad::softplus(x);
    case Activation::kElu:
      return ad::elu(x);
    case Activation::kSelu:
      return ad::selu(x);
    case Activation::kSwish:
      return ad::swish(x);
  }
  throw std::invalid_argument(fmt::format("activate: unknown activation {}", int(activation)));
}

template ad::Var<float> activate(Activation, const ad::Var<float>&);
template ad::Var<double> activate(Activation, const ad::Var<double>&);

}  // namespace hnn::nn
