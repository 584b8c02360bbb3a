// Ground-truth trajectories for tasks: a system's states at requested times,
// in closed form when it has one, else by tight adaptive integration.
#pragma once

#include "physics/integrator.h"
#include "physics/system.h"

namespace hnn::physics {

struct SimulateOptions {
  double rtol = 1e-9;     ///< docs/tasks.md integrates at rtol 1e-9 (1e-10 for the spring)
  double atol = 1e-12;    ///< tight, so rtol governs (SciPy's default 1e-6 would not)
  bool use_exact = true;  ///< use the closed form when the system has one
};

/// From each row of x0 at t_eval[0], the states at every t_eval: exact for the
/// spring, else Dopri5 at (rtol, atol).
Trajectory simulate(const System& system, const Batch& x0, const std::vector<double>& t_eval,
                    const SimulateOptions& options = {});

/// Integrates a system with any integrator. Splitting methods use the system's
/// exact halves (System::separable_split(): half the work of splitting the full
/// field) and throw std::invalid_argument naming midpoint, rk4 and dopri5 when
/// the system is not separable.
Trajectory integrate_system(const Integrator& integrator, const System& system, const Batch& x0,
                            const std::vector<double>& t_eval);

}  // namespace hnn::physics
