#pragma once
// hnn.Model: one learned dynamics model (nn/dynamics.h: an HNN, a D-HNN, a baseline or an LNN)
// in float32 or float64, with NumPy states in and out. hnn/__init__.py makes them (hnn.HNN, ...).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "nn/dynamics.h"

namespace hnn::python {

namespace py = pybind11;

/// What a Model is made from: the library's config, the scalar type and the seed of its weights.
struct ModelSpec {
  nn::DynamicsConfig config{};
  bool float32 = false;
  std::uint64_t seed = 0;
};

/// What Model::fit trains with (the training loop's, tasks/train/loop.h).
struct FitSpec {
  long steps = 1000;
  double lr = 1e-3;
  long batch = 0;  // 0: the full batch
  std::uint64_t seed = 0;
  long record_every = 1;
  double weight_decay = 0;
  py::object callback = py::none();  // called with (step, loss) at each loss-history point
  // The rollout loss's (fit_rollout): sampling intervals per window, the integrator, its step
  // (0: one step per interval).
  int horizon = 1;
  std::string integrator = "rk4";
  double dt = 0;
  /// The fit's task settings, as `hnn train`'s ("fit", "sampler", "rcond", ...:
  /// tasks/train/fit_method.h), a JSON object.
  std::string fit = "{}";
};

class Model {
 public:
  explicit Model(const ModelSpec& spec);
  template <typename T>
  explicit Model(std::unique_ptr<nn::DynamicsModel<T>> model) : model_(std::move(model)) {}

  /// A model from a parameter file written by save() or the hnn program (its kind, activation
  /// and widths are in the file; `angles` and `kinetic_prior` are not, and must be given when
  /// they are not the defaults); or the model of a run folder (one holding metrics.json).
  static Model load(const std::filesystem::path& path, long angles, double kinetic_prior);

  const nn::DynamicsConfig& config() const;
  std::string name() const;
  std::string dtype() const;
  std::string describe() const;

  py::array vector_field(const py::handle& x) const;
  py::array hamiltonian(const py::handle& x) const;
  py::dict parameters() const;
  void set_parameters(const py::dict& values);
  void save(const std::filesystem::path& path) const;
  /// The learned scalar (an HNN's H, an LNN's L) differentiated `order` times in the state,
  /// row by row: [batch, dim, ..., dim] (autodiff.cpp).
  py::array derivative(const py::handle& x, int order) const;
  /// d f / dx of the field, row by row: [batch, dim (f), dim (x)].
  py::array field_jacobian(const py::handle& x) const;
  /// Trains on (x, dxdt) with the library's loop and field objective; the loss history.
  py::array fit(const py::handle& x, const py::handle& dxdt, const FitSpec& spec);
  /// Trains through an integrator on trajectories [len(t), batch, dim] at times t (the rollout
  /// loss, tasks/train/rollout_objective.h); the loss history.
  py::array fit_rollout(const py::handle& paths, const py::handle& t, const FitSpec& spec);
  /// The model's field integrated from each row of x0 at t[0]: [len(t), batch, dim], float64.
  py::array rollout(const py::handle& x0, const py::handle& t, const std::string& integrator,
                    double rtol, double dt) const;

 private:
  /// Runs `train(model, stop)` with the GIL released and Ctrl-C as a stop request; the train
  /// losses of the curve it returns.
  template <typename Train>
  py::array trained(Train&& train);

  template <typename F>
  decltype(auto) visit(F&& f) const {
    return std::visit([&](const auto& m) -> decltype(auto) { return f(*m); }, model_);
  }

  std::variant<std::unique_ptr<nn::DynamicsModel<float>>,
               std::unique_ptr<nn::DynamicsModel<double>>>
      model_;
};

/// Adds hnn.Model to the module.
void bind_model(py::module_& m);
/// Adds the compiled half of hnn.autodiff.
void bind_autodiff(py::module_& m);

}  // namespace hnn::python
