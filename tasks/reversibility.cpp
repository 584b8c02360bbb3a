// Forward-then-backward integration of learned fields and the volume change of their flow maps,
// for any task's run folder, and the report over a results folder.

#include "tasks/reversibility.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <chrono>
#include <cmath>

#include "physics/integrator.h"
#include "tasks/files.h"
#include "tasks/pixel_pendulum.h"
#include "tasks/run.h"
#include "tasks/task.h"
#include "tasks/task_library.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

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

json reversibility(const fs::path& run_dir, const ReversibilityOptions& options) {
  ReversibilityOptions o = options;
  json result;
  if (pixel::is_pixel_run(run_dir)) {
    const pixel::LoadedPixelRun run = pixel::load_pixel_run(run_dir);
    if (o.t_end <= 0) o.t_end = run.config.rollout_frames;
    const int n = std::min(o.trajectories, run.data.test_trials());
    std::vector<Eigen::Index> rows;
    for (int i = 0; i < n; ++i) rows.push_back(Eigen::Index(i) * run.data.pairs_per_trial());
    const physics::Batch z0 = run.model->encode(run.data.pairs_of<double>(rows, false));
    result = measure_reversibility(run.model->dynamics(), z0, o);
    result.update({{"task", pixel::kTaskName}, {"model", run.options.model}, {"space", "latent"}});
  } else {
    const LoadedRun run = load_run(run_dir);
    const RolloutConfig rollout = run.task->rollout_config();
    if (o.t_end <= 0) o.t_end = rollout.t_end;
    std::mt19937_64 rng(run.options.seed + 1);  // the evaluation's rollout states
    physics::Batch x0 = run.task->rollout_states(run.data, rng);
    x0.conservativeResize(std::min<Eigen::Index>(x0.rows(), o.trajectories), Eigen::NoChange);
    result = measure_reversibility(*run.model, x0, o);
    result.update({{"task", run.options.task}, {"model", run.options.model}, {"space", "state"}});
  }
  write_file_atomic(run_dir / "reversibility.json", result.dump(2) + "\n");
  return result;
}

json reversibility_report(const fs::path& results, const ReversibilityOptions& options) {
  json rows = json::array();
  std::string failures;
  std::string md =
      "# Reversibility\n\n"
      "Each trained model's field integrated forward over the task's rollout span and back "
      "again; mean Euclidean distance between the start and the return, over the rollout "
      "states (pixel pendulum: encoded test pairs, latent space). Implicit midpoint is "
      "symmetric, so it returns for any field up to its solver tolerance; RK4 (dt = span/1000) "
      "and dopri5 (rtol 1e-9) are not, and show how the field amplifies their errors. det: mean "
      "determinant of the flow map's Jacobian over the span (1 = volume kept, Liouville).\n\n"
      "| task | model | midpoint | rk4 | dopri5 | det |\n| --- | --- | --- | --- | --- | --- |\n";
  for (const std::string& task : task_names()) {
    for (const char* model : {"baseline", "hnn"}) {
      fs::path dir = results / task / model;
      if (!fs::exists(dir / "metrics.json")) dir /= "seed-0";
      if (!fs::exists(dir / "metrics.json")) continue;
      const json r = reversibility(dir, options);
      rows.push_back(r);
      std::string line = fmt::format("| {} | {} |", task, model);
      for (const char* name : {"midpoint", "rk4", "dopri5"}) {
        std::string value = "n/a";
        for (const json& i : r["integrators"]) {
          if (i["integrator"] != name) continue;
          value = i.contains("failure") ? "failed"
                  : i["return_distance_mean"].is_number()
                      ? fmt::format("{:.2e}", i["return_distance_mean"].get<double>())
                      : "n/a";
        }
        line += " " + value + " |";
      }
      const json& v = r["volume"];
      line += v.contains("det_mean") && v["det_mean"].is_number()
                  ? fmt::format(" {:.4g} |\n", v["det_mean"].get<double>())
                  : " n/a |\n";
      md += line;
      for (const json& i : r["integrators"]) {
        if (i.contains("failure"))
          failures += fmt::format("- {} {}: {}\n", task, model, i["failure"].get<std::string>());
      }
      if (v.contains("failure")) {
        failures += fmt::format("- {} {}, det: {}\n", task, model, v["failure"].get<std::string>());
      }
    }
  }
  if (!failures.empty()) md += "\nWhy a cell says failed or n/a:\n\n" + failures;
  write_file_atomic(results / "reversibility.json", rows.dump(2) + "\n");
  write_file_atomic(results / "reversibility.md", md);
  return rows;
}

}  // namespace hnn::tasks
