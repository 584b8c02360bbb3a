#pragma once
// Modules and their parameters: persistent, named ad::Var leaves that a module owns, lists for
// optimisers and checkpoints, and copies between float and double models.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "autodiff/var.h"

namespace hnn::nn {

using Index = Eigen::Index;
template <typename T>
using Matrix = ad::Matrix<T>;
template <typename T>
using MatrixView = ad::MatrixView<T>;

/// A parameter and its dotted path in the module tree ("layers.0.weight").
template <typename T>
struct NamedParameter {
  std::string name;
  ad::Var<T> var;
};

/// Called once per parameter, in a fixed order, with its name and its handle. Assigning to the
/// handle rebinds the module to another leaf (bind_parameters uses this).
template <typename T>
using ParameterVisitor = std::function<void(const std::string& name, ad::Var<T>& parameter)>;

/// Base of every layer and model. Modules are move-only: a copy would share its leaves with the
/// original (the Var handles alias), so deep copies go through cast<U>() / copy_parameters.
template <typename T>
class Module {
 public:
  using Scalar = T;
  virtual ~Module() = default;

  /// Visits every parameter in a fixed order (the order of parameters() and of checkpoints).
  virtual void visit_parameters(const ParameterVisitor<T>& visit) = 0;
  /// What the module computes, beyond its parameter shapes ("mlp:tanh", "hnn:tanh"): stored in
  /// checkpoints, which refuse to load into a module of another kind.
  virtual std::string kind() const = 0;

  std::vector<NamedParameter<T>> named_parameters() const;
  std::vector<ad::Var<T>> parameters() const;
  /// Total number of scalars in the parameters.
  Index parameter_count() const;
  /// Turns gradient tracking of every parameter on or off (e.g. to freeze a submodel).
  void set_requires_grad(bool on);
  /// Replaces the parameter handles, in visit order, by `leaves` (same count and shapes). Used to
  /// differentiate a module with respect to leaves made elsewhere (gradcheck).
  void bind_parameters(const std::vector<ad::Var<T>>& leaves);

 protected:
  Module() = default;
  Module(Module&&) noexcept = default;
  Module& operator=(Module&&) noexcept = default;
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;
};

/// Calls `visit` for each parameter of `child` with its name prefixed by "prefix.".
template <typename T>
void visit_child(Module<T>& child, const std::string& prefix, const ParameterVisitor<T>& visit) {
  child.visit_parameters(
      [&](const std::string& name, ad::Var<T>& p) { visit(prefix + "." + name, p); });
}

/// Copies every parameter value of `from` into `to`, converting the scalar type. Both must have
/// the same parameter names and shapes (kinds are not compared); nothing is changed when they
/// differ (throws std::invalid_argument naming the first difference).
template <typename From, typename To>
void copy_parameters(const Module<From>& from, Module<To>& to);

}  // namespace hnn::nn
