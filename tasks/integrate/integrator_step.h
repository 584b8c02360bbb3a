#pragma once
// One step of an integrator through a model's field x' = f(x), recorded on the tape so that a
// loss on the states it reaches differentiates through it (and, for an HNN, through the field:
// a second-order path). The state is the model's carried one (DynamicsModel::integrated_state:
// the observed x for every model but the mass HNN, which carries (q, p)), q the first half of the
// columns; a model only supplies integrated_derivative, so every method works for hnn, baseline
// and dhnn alike.
//
// - rk4: the classical Runge-Kutta method, order 4, not symplectic.
// - leapfrog: kick-drift-kick on the field's p-part and q-part,
//     p' = p + h/2 f_p(q, p);  q1 = q + h f_q(q, p');  p1 = p' + h/2 f_p(q1, p').
//   For a separable H (f_p depends on q alone, f_q on p alone) it is Stormer-Verlet: symplectic,
//   order 2. For a field that is not separable (a learned H(q, p) in general) it is an explicit
//   method of order 1 only: the kicks miss the h^2/2 (df_p/dp) f_p term and the drift the
//   h^2/2 (df_q/dq) f_q term (tests/tasks/rollout_integrators_test.cpp measures both orders).
// - yoshida4: Yoshida's triple jump of leapfrog (steps w1 h, w0 h, w1 h), order 4 for a
//   separable H, symplectic there.
// - midpoint: the implicit midpoint rule x1 = x0 + h f((x0 + x1)/2), order 2, symplectic for ANY
//   H, separable or not. Solved off the tape (Note [Midpoint on the tape]).
//
// Training steps through them (the rollout loss, tasks/train/rollout_objective.h) and so does
// evaluation (a rollout-trained model along held-out stretches, tasks/evaluate/held_out.h), so
// they sit in a folder below both.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "autodiff/var.h"
#include "nn/dynamics.h"

namespace hnn::tasks {

/// kRk38 is Kutta's 3/8 rule, the fourth-order RK that torchdiffeq's "rk4" runs
/// (rk4_alt_step_func), so the peers' rollout losses through "rk4" are that method.
enum class RolloutIntegrator { kRk4, kLeapfrog, kYoshida4, kMidpoint, kRk38 };

std::string_view to_string(RolloutIntegrator integrator);
/// Throws Error naming the valid names.
RolloutIntegrator parse_rollout_integrator(std::string_view name);
std::vector<std::string> rollout_integrator_names();

/// The implicit midpoint's solve: converged when max |dx| / (1 + |x|) <= tolerance.
struct MidpointSolve {
  double tolerance = 0;  ///< 0: 1e-12 in double, 1e-5 in float
  int max_iterations = 50;
};

/// Midpoint iterations used so far on this thread (tests and reports).
long midpoint_iterations();

/// One step of size h (a column: one length per row) from x, on the tape unless grad mode is
/// off. Throws Error when the midpoint solve does not converge, naming the row and residual.
template <typename T>
ad::Var<T> integrator_step(const nn::DynamicsModel<T>& model, const ad::Var<T>& x,
                           const ad::Var<T>& h, RolloutIntegrator method,
                           const MidpointSolve& solve = {});

/// A known field, z -> dz/dt on a batch of rows (a true system's vector_field).
using KnownField = std::function<void(const ad::Matrix<double>& z, ad::Matrix<double>& dzdt)>;

/// One step of size h (a column) of an explicit `method` through a known field, as values: the
/// formulas integrator_step runs, so that the true system through a run's integrator is measured
/// alike (FieldTraining::truth_loss). Throws Error for the midpoint, whose solve needs the
/// field's Jacobian.
ad::Matrix<double> known_field_step(const KnownField& field, const ad::Matrix<double>& x,
                                    const ad::Matrix<double>& h, RolloutIntegrator method);

/// The converged implicit-midpoint step as plain values, off the tape: x1 with
/// x1 = x0 + h f((x0 + x1)/2) for every row (h a column). The map the on-tape step differentiates.
template <typename T>
ad::Matrix<T> midpoint_solve(const nn::DynamicsModel<T>& model, const ad::Matrix<T>& x0,
                             const ad::Matrix<T>& h, const MidpointSolve& solve = {});

/// d f_r / d x_r for every row r of x, flattened row-major (R x n^2), as plain values.
template <typename T>
ad::Matrix<T> field_row_jacobian(const nn::DynamicsModel<T>& model, const ad::Matrix<T>& x);

}  // namespace hnn::tasks
