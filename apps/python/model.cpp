#include "apps/python/model.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <random>

#include "apps/python/arrays.h"
#include "nn/hnn.h"
#include "nn/lnn.h"
#include "nn/parameter_file.h"
#include "physics/integrator.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/run.h"

namespace hnn::python {

namespace fs = std::filesystem;

namespace {

template <typename T>
std::unique_ptr<nn::DynamicsModel<T>> made(const ModelSpec& spec) {
  std::mt19937_64 rng(spec.seed);
  return nn::make_model<T>(spec.config, rng);
}

// What a parameter file says of its model: the kind and activation ("hnn:tanh") and the widths
// of its layers ("mlp.layers.<i>.weight", in x out).
ModelSpec spec_of_file(const fs::path& path, long angles, double kinetic_prior) {
  const nn::ParameterFileInfo info = nn::read_parameter_file_info(path);
  const std::size_t colon = info.kind.find(':');
  if (colon == std::string::npos)
    throw InputError(fmt::format("{}: the file's kind '{}' is not a dynamics model's",
                                 path.string(), info.kind));
  const std::string name = info.kind.substr(0, colon);
  ModelSpec spec{.float32 = info.scalar == nn::ScalarType::kFloat32};
  nn::DynamicsConfig& c = spec.config;
  if (name == "hnn-dissipative") {
    c.model = nn::ModelKind::kDhnn;
    c.field = nn::FieldType::kBoth;
  } else if (name == "hnn-conservative") {
    c.field = nn::FieldType::kConservative;
  } else {
    c.model = nn::parse_model_kind(name);  // hnn, baseline, lnn, hnn-mass
  }
  c.activation = nn::parse_activation(info.kind.substr(colon + 1));
  std::vector<Eigen::Index> widths;
  for (const nn::ParameterFileInfo::Entry& e : info.entries) {
    if (e.name.starts_with("mlp.") && e.name.ends_with(".weight")) {  // a mass HNN's V
      if (widths.empty()) widths.push_back(e.rows);
      widths.push_back(e.cols);
    }
  }
  if (widths.size() < 2)
    throw InputError(fmt::format("{}: the file holds no layers of a model", path.string()));
  c.angles = angles;
  c.dim = widths.front() - angles;                     // an angle is seen as (cos, sin)
  if (c.model == nn::ModelKind::kMassHnn) c.dim *= 2;  // its MLPs see the positions alone
  c.hidden.assign(widths.begin() + 1, widths.end() - 1);
  c.kinetic_prior = kinetic_prior;
  return spec;
}

}  // namespace

Model::Model(const ModelSpec& spec) {
  nn::validate(spec.config);
  if (spec.float32) {
    model_ = made<float>(spec);
  } else {
    model_ = made<double>(spec);
  }
}

Model Model::load(const fs::path& path, long angles, double kinetic_prior) {
  if (fs::is_directory(path)) {  // a run folder: the model as the run's user sees it
    const tasks::LoadedRun run = tasks::load_run(path);
    return Model(run.run->model_in_data_units());
  }
  Model model(spec_of_file(path, angles, kinetic_prior));
  model.visit([&](auto& m) { nn::load_parameters(path, m); });
  return model;
}

const nn::DynamicsConfig& Model::config() const {
  return visit([](const auto& m) -> const nn::DynamicsConfig& { return m.config(); });
}
std::string Model::name() const {
  return visit([](const auto& m) { return m.name(); });
}
std::string Model::dtype() const {
  return std::holds_alternative<std::unique_ptr<nn::DynamicsModel<float>>>(model_) ? "float32"
                                                                                   : "float64";
}
std::string Model::describe() const {
  return visit([&](const auto& m) { return fmt::format("{} {}", m.describe(), dtype()); });
}

py::array Model::vector_field(const py::handle& x) const {
  return visit([&]<typename T>(const nn::DynamicsModel<T>& m) {
    const StatesIn<T> states(x, "x", m.dim());
    Matrix<T> f;
    {
      py::gil_scoped_release free;
      f = m.field(states.view());
    }
    return to_array(f);
  });
}

py::array Model::hamiltonian(const py::handle& x) const {
  return visit([&]<typename T>(const nn::DynamicsModel<T>& m) {
    const StatesIn<T> states(x, "x", m.dim());
    if (!m.has_learned_energy())
      throw InputError(fmt::format("hamiltonian: a {} model learns no H", m.name()));
    const Matrix<T> h = m.learned_energy(states.view());  // an LNN's: v . dL/dv - L
    return to_array(h, {h.rows()});
  });
}

py::dict Model::parameters() const {
  py::dict out;
  visit([&](const auto& m) {
    for (const auto& p : m.named_parameters()) out[py::str(p.name)] = to_array(p.var.value());
  });
  return out;
}

void Model::set_parameters(const py::dict& values) {
  visit([&]<typename T>(const nn::DynamicsModel<T>& m) {
    const std::vector<nn::NamedParameter<T>> params = m.named_parameters();
    std::vector<std::string> names;
    for (const auto& p : params) names.push_back(p.name);
    for (const auto& [key, value] : values) {
      const std::string name = py::str(key);
      if (std::find(names.begin(), names.end(), name) == names.end())
        throw InputError(fmt::format("set_parameters: unknown parameter '{}' (the model's: {})",
                                     name, fmt::join(names, ", ")));
    }
    std::vector<Matrix<T>> checked;  // every value checked before any is set
    for (const auto& p : params) {
      if (!values.contains(p.name))
        throw InputError(fmt::format("set_parameters: '{}' is missing", p.name));
      const py::array value = py::array::ensure(values[py::str(p.name)]);
      if (!value || value.ndim() != 2 || value.shape(0) != p.var.rows() ||
          value.shape(1) != p.var.cols())
        throw InputError(fmt::format("set_parameters: '{}' must be an array of {} x {}", p.name,
                                     p.var.rows(), p.var.cols()));
      checked.push_back(states<T>(value, "set_parameters: " + p.name, p.var.cols()));
    }
    for (std::size_t i = 0; i < params.size(); ++i) {
      ad::Var<T> leaf = params[i].var;
      leaf.mutable_value() = checked[i];
    }
  });
}

void Model::save(const fs::path& path) const {
  visit([&](const auto& m) { nn::save_parameters(path, m); });
}

py::array Model::rollout(const py::handle& x0, const py::handle& t, const std::string& integrator,
                         double rtol, double dt) const {
  const std::vector<double> times = python::times(t, "t");
  const physics::Batch start = states<double>(x0, "x0", config().dim);
  const auto stepper =
      physics::make_integrator(integrator, {.dt = dt, .rtol = rtol, .atol = rtol * 1e-3});
  physics::Trajectory path;
  {
    py::gil_scoped_release free;
    // Rollouts run in double (as the hnn program's: tasks/trained_model.h says why).
    const auto in_double = visit([](const auto& m) { return nn::cast_model<double>(m); });
    path = stepper->integrate(tasks::learned_field(*in_double).field, start, times);
  }
  return to_array(path);
}

}  // namespace hnn::python
