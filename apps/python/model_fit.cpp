// hnn.Model.fit, on the library's training loop (tasks/train/loop.h) and its objectives: the
// field's (tasks/train/field_objective.h) and through an integrator
// (tasks/train/rollout_objective.h); and the bindings of hnn.Model.

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "apps/python/arrays.h"
#include "apps/python/interrupt.h"
#include "apps/python/model.h"
#include "nn/sampled/sampled_fit.h"
#include "tasks/error.h"
#include "tasks/options/fit_options.h"
#include "tasks/train/field_objective.h"
#include "tasks/train/fit_method.h"
#include "tasks/train/loop.h"
#include "tasks/train/rollout_objective.h"

namespace hnn::python {

namespace {

// An objective of tasks/train/ keeping its last loss-curve point for fit's callback.
template <class Objective>
class Reporting : public Objective {
 public:
  using Objective::Objective;
  tasks::CurvePoint curve_point(long step, double batch_loss) const override {
    last = Objective::curve_point(step, batch_loss);
    return last;
  }
  mutable tasks::CurvePoint last{};
};

// The training loop on `objective`, quiet, with fit's callback at each loss-curve point.
template <class Objective>
tasks::TrainResult run_loop(Reporting<Objective>& objective, const FitSpec& spec,
                            tasks::StopSignal* stop) {
  tasks::LoopOptions loop{.steps = spec.steps,
                          .record_every = spec.record_every,
                          .quiet = true,
                          .label = "fit",
                          .stop = stop};
  if (!spec.callback.is_none()) {
    loop.on_record = [&](long step) {
      py::gil_scoped_acquire hold;  // a Python exception it raises ends the fit
      spec.callback(step, objective.last.train_loss);
    };
  }
  return tasks::train(objective, loop);
}

void check_spec(const FitSpec& spec, Eigen::Index rows, std::string_view what) {
  HNN_TASKS_CHECK(spec.batch >= 0 && spec.batch <= rows,
                  "batch must be 0 (the full batch) to {} (the {}), got {}", rows, what,
                  spec.batch);
  HNN_TASKS_CHECK(spec.record_every >= 1, "record_every must be >= 1, got {}", spec.record_every);
}

// Each trajectory of `paths` ([times, batch, dim]) as a stretch at times t.
std::vector<tasks::Stretch> stretches(const py::handle& paths, const py::handle& t,
                                      Eigen::Index dim) {
  const std::vector<double> times = python::times(t, "t");
  std::vector<tasks::Stretch> out;
  for (physics::Batch& path : trajectories(paths, "trajectories", Eigen::Index(times.size()), dim))
    out.push_back({Eigen::Map<const Eigen::VectorXd>(times.data(), Eigen::Index(times.size())),
                   std::move(path)});
  return out;
}

}  // namespace

template <typename Train>
py::array Model::trained(Train&& train) {
  tasks::TrainResult result;
  {
    Interrupt interrupt;
    try {
      py::gil_scoped_release free;
      result = std::visit([&](auto& m) { return train(*m, interrupt.signal()); }, model_);
    } catch (const tasks::TrainingInterrupted&) {
      Interrupt::raise_keyboard_interrupt();  // the model is left at its last finished step
    }
  }
  Eigen::VectorXd losses(Eigen::Index(result.curve.size()));
  for (std::size_t i = 0; i < result.curve.size(); ++i)
    losses(Eigen::Index(i)) = result.curve[i].train_loss;
  return to_array(losses);
}

py::array Model::fit(const py::handle& x, const py::handle& dxdt, const FitSpec& spec) {
  const Eigen::Index dim = config().dim;
  tasks::Dataset data{.train_x = states<double>(x, "x", dim),
                      .train_dxdt = states<double>(dxdt, "dxdt", dim),
                      .test_x = {},
                      .test_dxdt = {}};
  if (data.train_dxdt.rows() != data.train_x.rows())
    throw InputError(fmt::format("dxdt: expected {} rows, one per state of x, got {}",
                                 data.train_x.rows(), data.train_dxdt.rows()));
  check_spec(spec, data.train_x.rows(), "rows of x");
  const tasks::FitConfig method = tasks::fit_config(nlohmann::json::parse(spec.fit), "fit");
  if (method.samples()) {
    tasks::check_fit_model(method, config().model, "fit");
    nn::SampledFitConfig sampled = method.sampled;
    sampled.seed = spec.seed;
    double mse = 0;
    {
      py::gil_scoped_release free;
      visit([&](auto& m) {
        nn::fit_sampled(m, data.train_x, data.train_dxdt, sampled);
        mse = tasks::field_mse(m, data.train_x, data.train_dxdt);
      });
    }
    if (!method.steps()) return to_array(Eigen::VectorXd::Constant(1, mse));
  }
  const nn::AdamOptions adam{.lr = spec.lr, .weight_decay = spec.weight_decay};
  return trained([&]<typename T>(nn::DynamicsModel<T>& m, tasks::StopSignal* stop) {
    Reporting<tasks::FieldObjective<T>> objective(m, data, spec.batch, adam, spec.seed);
    return run_loop(objective, spec, stop);
  });
}

py::array Model::fit_rollout(const py::handle& paths, const py::handle& t, const FitSpec& spec) {
  const tasks::RolloutWindows windows =
      tasks::rollout_windows(stretches(paths, t, config().dim), spec.horizon);
  const int substeps = tasks::rollout_substeps(windows, spec.dt);
  const tasks::RolloutIntegrator integrator = tasks::parse_rollout_integrator(spec.integrator);
  check_spec(spec, windows.count(), "rollout windows");
  const nn::AdamOptions adam{.lr = spec.lr, .weight_decay = spec.weight_decay};
  return trained([&]<typename T>(nn::DynamicsModel<T>& m, tasks::StopSignal* stop) {
    Reporting<tasks::RolloutObjective<T>> objective(m, windows, tasks::RolloutWindows{}, spec.batch,
                                                    adam, spec.seed, integrator, substeps);
    return run_loop(objective, spec, stop);
  });
}

void bind_model(py::module_& m) {
  py::class_<FitSpec>(m, "_FitSpec")
      .def(py::init<>())
      .def_readwrite("steps", &FitSpec::steps)
      .def_readwrite("lr", &FitSpec::lr)
      .def_readwrite("batch", &FitSpec::batch)
      .def_readwrite("seed", &FitSpec::seed)
      .def_readwrite("record_every", &FitSpec::record_every)
      .def_readwrite("weight_decay", &FitSpec::weight_decay)
      .def_readwrite("callback", &FitSpec::callback)
      .def_readwrite("horizon", &FitSpec::horizon)
      .def_readwrite("integrator", &FitSpec::integrator)
      .def_readwrite("dt", &FitSpec::dt)
      .def_readwrite("fit", &FitSpec::fit);
  py::class_<Model>(m, "Model",
                    "A learned dynamics model: hnn.HNN, hnn.DHNN, hnn.Baseline, hnn.LNN.")
      .def(py::init([](const std::string& kind, long dim, std::vector<long> hidden,
                       const std::string& activation, const std::string& dtype, std::uint64_t seed,
                       long angles, double kinetic_prior) {
             if (dtype != "float32" && dtype != "float64")
               throw InputError(fmt::format("dtype must be float32 or float64, got '{}'", dtype));
             ModelSpec spec{.float32 = dtype == "float32", .seed = seed};
             spec.config.model = nn::parse_model_kind(kind);
             if (spec.config.model == nn::ModelKind::kDhnn)
               spec.config.field = nn::FieldType::kBoth;
             spec.config.dim = dim;
             spec.config.hidden.assign(hidden.begin(), hidden.end());
             spec.config.activation = nn::parse_activation(activation);
             spec.config.angles = angles;
             spec.config.kinetic_prior = kinetic_prior;
             return Model(spec);
           }),
           py::arg("kind"), py::arg("dim"), py::arg("hidden"), py::arg("activation"),
           py::arg("dtype"), py::arg("seed"), py::arg("angles"), py::arg("kinetic_prior"))
      .def_static("load", &Model::load, py::arg("path"), py::arg("angles") = 0,
                  py::arg("kinetic_prior") = 1.0)
      .def_property_readonly(
          "dim", [](const Model& self) { return self.config().dim; }, "The state's size 2n")
      .def_property_readonly("kind", &Model::name, "hnn, hnn-dissipative, baseline or lnn")
      .def_property_readonly("dtype", &Model::dtype, "float32 or float64")
      .def("__repr__", [](const Model& self) { return "<hnn.Model " + self.describe() + ">"; })
      .def("vector_field", &Model::vector_field, py::arg("x"),
           "dx/dt at each state (row) of x, [batch, dim]")
      .def("hamiltonian", &Model::hamiltonian, py::arg("x"),
           "The learned H at each state of x (an LNN: its energy), [batch]")
      .def("parameters", &Model::parameters, "The parameters by name, as new arrays")
      .def("set_parameters", &Model::set_parameters, py::arg("values"),
           "Sets every parameter from a dict like parameters()'s (all or none)")
      .def("save", &Model::save, py::arg("path"),
           "Writes the parameters in the hnn program's file format (params.bin)")
      .def("_derivative", &Model::derivative, py::arg("x"), py::arg("order"))
      .def("_field_jacobian", &Model::field_jacobian, py::arg("x"))
      .def("_fit", &Model::fit, py::arg("x"), py::arg("dxdt"), py::arg("spec"))
      .def("_fit_rollout", &Model::fit_rollout, py::arg("trajectories"), py::arg("t"),
           py::arg("spec"))
      .def("rollout", &Model::rollout, py::arg("x0"), py::arg("t"),
           py::arg("integrator") = "dopri5", py::arg("rtol") = 1e-9, py::arg("dt") = 1e-2,
           "The learned field integrated from each row of x0 at t[0], [len(t), batch, dim]");
}

}  // namespace hnn::python
