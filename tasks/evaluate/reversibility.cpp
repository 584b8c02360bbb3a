// Forward-then-backward integration of a learned field and the volume change of its flow map.

#include "tasks/evaluate/reversibility.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <chrono>
#include <cmath>

#include "physics/integrator.h"
#include "tasks/error.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// A step budget for the probes: on a chaotic system (three-body) they separate until dopri5
// crawls for minutes, and a Jacobian by differences over such a span means nothing anyway.
constexpr long kVolumeMaxSteps = 5'000;

// det(d x(T) / d x0) for each row of x0, by central differences through dopri5, with steps h
// and h/2. Where the two determinants disagree, the flow stretches the probes beyond the
// linear regime (chaos, near-collisions) and the Jacobian is not resolved by differences:
// this throws then.
Eigen::VectorXd flow_determinants(const physics::VectorField& field, const physics::Batch& x0,
                                  double t_end) {
  const Eigen::Index n = x0.rows(), d = x0.cols();
  constexpr int kProbes = 4;  // x0 + h e_j, x0 - h e_j, x0 + h/2 e_j, x0 - h/2 e_j
  const auto row = [d](Eigen::Index i, Eigen::Index j, int k) { return (i * d + j) * kProbes + k; };
  physics::Batch probes(n * d * kProbes, d);
  Eigen::VectorXd step(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    step(i) = 1e-4 * std::max(1.0, x0.row(i).norm());
    for (Eigen::Index j = 0; j < d; ++j) {
      for (int k = 0; k < kProbes; ++k) {
        probes.row(row(i, j, k)) = x0.row(i);
        probes(row(i, j, k), j) += (k % 2 == 0 ? 1 : -1) * step(i) / (k < 2 ? 1 : 2);
      }
    }
  }
  const auto dopri = physics::make_integrator(
      "dopri5", {.rtol = 1e-11, .atol = 1e-13, .max_steps = kVolumeMaxSteps});
  const physics::Batch end = dopri->integrate(field, probes, {0.0, t_end}).states.back();
  Eigen::VectorXd det(n);
  long unresolved = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::MatrixXd coarse(d, d), fine(d, d);
    for (Eigen::Index j = 0; j < d; ++j) {
      coarse.col(j) = (end.row(row(i, j, 0)) - end.row(row(i, j, 1))).transpose() / (2 * step(i));
      fine.col(j) = (end.row(row(i, j, 2)) - end.row(row(i, j, 3))).transpose() / step(i);
    }
    det(i) = fine.determinant();
    const double disagreement = std::abs(det(i) - coarse.determinant());
    if (!(disagreement <= 1e-2 * std::max(1.0, std::abs(det(i))))) ++unresolved;
  }
  if (unresolved > 0) {
    throw Error(fmt::format(
        "the flow map's Jacobian is not resolved by differences on {} of {} states (steps h and "
        "h/2 give determinants over 1% apart: the flow stretches the probes beyond its linear "
        "regime by t = {})",
        unresolved, n, t_end));
  }
  return det;
}

}  // namespace

json measure_reversibility(const nn::DynamicsModel<double>& model, const physics::Batch& x0,
                           const ReversibilityOptions& o) {
  HNN_TASKS_CHECK(o.t_end > 0, "reversibility: the time span must be positive");
  const physics::VectorField field = [&model](double, const physics::Batch& x,
                                              physics::Batch& dxdt) { dxdt = model.field(x); };
  const double dt = o.dt > 0 ? o.dt : o.t_end / 1000;
  json out = {{"t_end", o.t_end}, {"dt", dt}, {"trajectories", x0.rows()}};
  for (const std::string& name : o.integrators) {
    const auto start = std::chrono::steady_clock::now();
    const auto integrator =
        physics::make_integrator(name, {.dt = dt, .rtol = o.rtol, .atol = o.rtol * 1e-3});
    json r = {{"integrator", name}};
    try {
      const physics::Trajectory fwd = integrator->integrate(field, x0, {0.0, o.t_end});
      const physics::Trajectory back =
          integrator->integrate(field, fwd.states.back(), {o.t_end, 0.0});
      const Eigen::VectorXd dist = (back.states.back() - x0).rowwise().norm();
      const Eigen::VectorXd scale = x0.rowwise().norm().cwiseMax(1e-12);
      r.update({{"return_distance_mean", number(dist.mean())},
                {"return_distance_max", number(dist.maxCoeff())},
                {"relative_return_mean", number(dist.cwiseQuotient(scale).mean())},
                {"travel_mean", number((fwd.states.back() - x0).rowwise().norm().mean())},
                {"nfev", fwd.stats.nfev + back.stats.nfev}});
    } catch (const physics::IntegrationError& e) {
      r["failure"] = e.what();
    }
    r["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out["integrators"].push_back(r);
  }
  try {
    const Eigen::VectorXd det = flow_determinants(field, x0, o.t_end);
    out["volume"] = {{"det_mean", number(det.mean())},
                     {"det_min", number(det.minCoeff())},
                     {"det_max", number(det.maxCoeff())},
                     {"abs_log_det_mean", number(det.array().abs().log().abs().mean())}};
  } catch (const physics::IntegrationError& e) {
    out["volume"] = {{"failure", e.what()}};
  } catch (const Error& e) {  // not resolved by differences
    out["volume"] = {{"failure", e.what()}};
  }
  return out;
}

}  // namespace hnn::tasks
