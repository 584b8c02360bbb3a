// hnn.systems: the library's Hamiltonian systems (physics/) with NumPy states in and out.

#include "apps/python/systems.h"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <memory>
#include <random>

#include "apps/python/arrays.h"
#include "physics/double_pendulum.h"
#include "physics/expression_system.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"
#include "physics/simulate.h"

namespace hnn::python {

namespace {

using physics::System;
using SystemPtr = std::shared_ptr<System>;

py::array system_hamiltonian(const System& s, const py::handle& x) {
  const StatesIn<double> states(x, "x", s.dim());
  return to_array(s.hamiltonian_batch(states.view()));
}

py::array system_field(const System& s, const py::handle& x) {
  physics::Batch dxdt;
  const StatesIn<double> states(x, "x", s.dim());
  s.vector_field(states.view(), dxdt);
  return to_array(dxdt);
}

// dopri5 at rtol (atol = rtol / 1000, as the hnn program's rollouts) or a fixed-step method at
// dt; splitting methods use the system's exact halves (physics/simulate.h).
py::array simulate(const System& s, const py::handle& x0, const py::handle& t,
                   const std::string& integrator, double rtol, double dt) {
  const std::vector<double> times = python::times(t, "t");
  const physics::Batch start = states<double>(x0, "x0", s.dim());
  const auto stepper =
      physics::make_integrator(integrator, {.dt = dt, .rtol = rtol, .atol = rtol * 1e-3});
  physics::Trajectory path;
  {
    py::gil_scoped_release free;
    path = physics::integrate_system(*stepper, s, start, times);
  }
  return to_array(path);
}

py::array initial_states(const System& s, int n, std::uint64_t seed) {
  if (n < 1) throw InputError(fmt::format("initial_states: n must be >= 1, got {}", n));
  std::mt19937_64 rng(seed);
  return to_array(Matrix<double>(s.sample_initial_states(n, rng)));
}

}  // namespace

void bind_systems(py::module_& m) {
  py::module_ s = m.def_submodule("_systems", "The library's Hamiltonian systems");
  py::class_<System, SystemPtr>(s, "System", "A Hamiltonian system in x = (q, p)")
      .def_property_readonly("dim", &System::dim, "The state's size 2n")
      .def_property_readonly("name", &System::name, "The system's name (an expression's H)")
      .def("__repr__",
           [](const System& self) { return "<hnn.systems.System " + self.name() + ">"; })
      .def("hamiltonian", &system_hamiltonian, py::arg("x"), "H at each state of x, [batch]")
      .def("vector_field", &system_field, py::arg("x"),
           "The exact dx/dt = (dH/dp, -dH/dq) at each state of x, [batch, dim]")
      .def("simulate", &simulate, py::arg("x0"), py::arg("t"), py::arg("integrator") = "dopri5",
           py::arg("rtol") = 1e-9, py::arg("dt") = 1e-2,
           "The states from each row of x0 at t[0] at every time of t, [len(t), batch, dim]")
      .def("initial_states", &initial_states, py::arg("n"), py::arg("seed") = 0,
           "n initial states drawn as the library's tasks draw them, [n, dim]");
  s.def("spring", [](double stiffness, double kinetic) -> SystemPtr {
    return std::make_shared<physics::Spring>(stiffness, kinetic);
  });
  s.def("pendulum", [](double potential, double kinetic) -> SystemPtr {
    return std::make_shared<physics::Pendulum>(potential, kinetic);
  });
  s.def("nbody", [](std::vector<double> masses, double gravity) -> SystemPtr {
    return std::make_shared<physics::NBody>(std::move(masses), gravity);
  });
  s.def("double_pendulum", [](double m1, double m2, double l1, double l2, double g) -> SystemPtr {
    return std::make_shared<physics::DoublePendulum>(m1, m2, l1, l2, g);
  });
  s.def("expression",
        [](std::string h, std::vector<std::string> coords,
           std::vector<std::string> momenta) -> SystemPtr {
          return std::make_shared<physics::ExpressionSystem>(std::move(h), std::move(coords),
                                                             std::move(momenta));
        });
}

}  // namespace hnn::python
