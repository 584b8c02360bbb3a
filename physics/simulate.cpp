// simulate() and integrate_system(): pick the right route for a system.
#include "physics/simulate.h"

#include <fmt/format.h>

#include <stdexcept>

#include "physics/dopri5.h"
#include "physics/splitting.h"

namespace hnn::physics {

Trajectory simulate(const System& system, const Batch& x0, const std::vector<double>& t_eval,
                    const SimulateOptions& options) {
  validate_times(t_eval);
  if (x0.cols() != system.dim()) {
    throw std::invalid_argument(fmt::format("simulate: {} states have {} columns, x0 has {}",
                                            system.name(), system.dim(), x0.cols()));
  }
  if (options.use_exact && system.exact_flow(x0, 0.0)) {
    Trajectory out;
    out.t = t_eval;
    for (double t : t_eval) out.states.push_back(*system.exact_flow(x0, t - t_eval[0]));
    return out;
  }
  IntegratorOptions o;
  o.rtol = options.rtol;
  o.atol = options.atol;
  return Dopri5(o).integrate(system.field(), x0, t_eval);
}

Trajectory integrate_system(const Integrator& integrator, const System& system, const Batch& x0,
                            const std::vector<double>& t_eval) {
  const auto* splitting = dynamic_cast<const SplittingIntegrator*>(&integrator);
  if (splitting == nullptr) return integrator.integrate(system.field(), x0, t_eval);
  const std::optional<SplitField> halves = system.separable_split();
  if (!halves) {
    throw std::invalid_argument(fmt::format(
        "{} needs a separable Hamiltonian H = T(p) + V(q); {} is not: use midpoint (symplectic), "
        "rk4 or dopri5",
        integrator.name(), system.name()));
  }
  return splitting->integrate(*halves, x0, t_eval);
}

}  // namespace hnn::physics
