// hnn.Model.fit, on the library's training loop (tasks/train/loop.h) and field objective
// (tasks/train/field_objective.h), and the bindings of hnn.Model.

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "apps/python/arrays.h"
#include "apps/python/interrupt.h"
#include "apps/python/model.h"
#include "tasks/error.h"
#include "tasks/train/field_objective.h"
#include "tasks/train/loop.h"

namespace hnn::python {

namespace {

// The field objective, keeping its last loss-curve point for fit's callback.
template <typename T>
class ReportingObjective : public tasks::FieldObjective<T> {
 public:
  using tasks::FieldObjective<T>::FieldObjective;
  tasks::CurvePoint curve_point(long step, double batch_loss) const override {
    last = tasks::FieldObjective<T>::curve_point(step, batch_loss);
    return last;
  }
  mutable tasks::CurvePoint last{};
};

template <typename T>
tasks::TrainResult fit_model(nn::DynamicsModel<T>& model, const tasks::Dataset& data,
                             const FitSpec& spec, tasks::StopSignal* stop) {
  ReportingObjective<T> objective(model, data, spec.batch,
                                  {.lr = spec.lr, .weight_decay = spec.weight_decay}, spec.seed);
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

}  // namespace

py::array Model::fit(const py::handle& x, const py::handle& dxdt, const FitSpec& spec) {
  const Eigen::Index dim = config().dim;
  tasks::Dataset data{.train_x = states<double>(x, "x", dim),
                      .train_dxdt = states<double>(dxdt, "dxdt", dim),
                      .test_x = {},
                      .test_dxdt = {}};
  if (data.train_dxdt.rows() != data.train_x.rows())
    throw InputError(fmt::format("dxdt: expected {} rows, one per state of x, got {}",
                                 data.train_x.rows(), data.train_dxdt.rows()));
  HNN_TASKS_CHECK(spec.batch >= 0 && spec.batch <= data.train_x.rows(),
                  "batch must be 0 (the full batch) to {} (the rows of x), got {}",
                  data.train_x.rows(), spec.batch);
  HNN_TASKS_CHECK(spec.record_every >= 1, "record_every must be >= 1, got {}", spec.record_every);
  tasks::TrainResult result;
  {
    Interrupt interrupt;
    try {
      py::gil_scoped_release free;
      result = std::visit([&](auto& m) { return fit_model(*m, data, spec, interrupt.signal()); },
                          model_);
    } catch (const tasks::TrainingInterrupted&) {
      Interrupt::raise_keyboard_interrupt();  // the model is left at its last finished step
    }
  }
  Eigen::VectorXd losses(Eigen::Index(result.curve.size()));
  for (std::size_t i = 0; i < result.curve.size(); ++i)
    losses(Eigen::Index(i)) = result.curve[i].train_loss;
  return to_array(losses);
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
      .def_readwrite("callback", &FitSpec::callback);
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
      .def_property_readonly("dim", [](const Model& self) { return self.config().dim; })
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
      .def("_fit", &Model::fit, py::arg("x"), py::arg("dxdt"), py::arg("spec"))
      .def("rollout", &Model::rollout, py::arg("x0"), py::arg("t"),
           py::arg("integrator") = "dopri5", py::arg("rtol") = 1e-9, py::arg("dt") = 1e-2,
           "The learned field integrated from each row of x0 at t[0], [len(t), batch, dim]");
}

}  // namespace hnn::python
