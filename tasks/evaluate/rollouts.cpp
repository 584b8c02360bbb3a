#include "tasks/evaluate/rollouts.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <random>
#include <stdexcept>

#include "autodiff/parallel.h"
#include "nn/dynamics.h"
#include "physics/integrator.h"
#include "physics/types.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

Eigen::MatrixXd integrate_one(const physics::VectorField& field, const Eigen::RowVectorXd& x0,
                              const std::vector<double>& t, const RolloutConfig& config, long* nfev,
                              long max_steps = physics::IntegratorOptions{}.max_steps) {
  const auto dopri = physics::make_integrator(
      "dopri5", {.rtol = config.rtol, .atol = config.atol, .max_steps = max_steps});
  const physics::Trajectory path = dopri->integrate(field, Batch(x0), t);
  if (nfev) *nfev += path.stats.nfev;
  return path.path(0);
}

// The grid's times and the horizons in one increasing list, and where each of them is in it.
struct Times {
  std::vector<double> all;
  std::vector<std::size_t> grid, horizons;
};

Times merge_times(const std::vector<double>& grid, const std::vector<double>& horizons) {
  Times out;
  out.all = grid;
  const double end = grid.empty() ? 0.0 : grid.back();
  const auto same = [&](double a, double b) { return std::abs(a - b) <= 1e-12 * (1 + end); };
  for (double h : horizons) {
    HNN_TASKS_CHECK(h > 0 && h <= end * (1 + 1e-12),
                    "rollouts: horizon {} is outside the rollout's span (0, {}]", h, end);
    if (std::none_of(out.all.begin(), out.all.end(), [&](double t) { return same(t, h); }))
      out.all.push_back(h);
  }
  std::sort(out.all.begin(), out.all.end());
  const auto at = [&](double t) {
    return std::size_t(
        std::find_if(out.all.begin(), out.all.end(), [&](double a) { return same(a, t); }) -
        out.all.begin());
  };
  for (double t : grid) out.grid.push_back(at(t));
  for (double h : horizons) out.horizons.push_back(at(h));
  return out;
}

// The rows of `path` at the given indices.
Eigen::MatrixXd pick(const Eigen::MatrixXd& path, const std::vector<std::size_t>& rows) {
  Eigen::MatrixXd out(Eigen::Index(rows.size()), path.cols());
  for (std::size_t k = 0; k < rows.size(); ++k)
    out.row(Eigen::Index(k)) = path.row(Eigen::Index(rows[k]));
  return out;
}

using EnergyFn = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;

// One learned rollout: its path, or why it failed (an integration that gives up, or a learned
// field that cannot be evaluated on the way: an LNN whose mass matrix turns singular).
struct LearnedPath {
  Eigen::MatrixXd path;
  long nfev = 0;
  std::string failure;  // empty: it finished
};

// The learned rollouts from every row of `starts`, appended to r in order, with the true energy
// along each (`energy`, if given) and the model's own H. The rollouts are shared among the
// engine's threads, one whole trajectory at a time (its field's products run on that thread
// alone, as with one thread: the same numbers at any thread count). The energies come after,
// on this thread: a system may be a GiNaC expression, which is not safe to share.
void add_learned(Rollouts& r, const LearnedField& learned, const Batch& starts, const Times& times,
                 const RolloutConfig& config, const EnergyFn& energy) {
  if (starts.rows() == 0) return;
  std::vector<LearnedPath> paths(std::size_t(starts.rows()));
  // One part per trajectory: the threads claim them in turn, as their costs differ.
  ad::parallel_for(int(starts.rows()), [&](int i) {
    LearnedPath& out = paths[std::size_t(i)];
    try {
      out.path = integrate_one(learned.field, starts.row(i), times.all, config, &out.nfev,
                               config.max_learned_steps);
    } catch (const std::exception& e) {
      out.failure = e.what();
    }
  });
  const Eigen::Index dim = starts.cols();
  for (LearnedPath& p : paths) {
    const Eigen::Index i = Eigen::Index(r.pred.size());
    r.nfev += p.nfev;
    r.failed.push_back(!p.failure.empty());
    if (!p.failure.empty()) {
      r.pred.push_back(Eigen::MatrixXd::Constant(Eigen::Index(times.grid.size()), dim, NAN));
      r.pred_at.push_back(Eigen::MatrixXd::Constant(Eigen::Index(times.horizons.size()), dim, NAN));
      r.failures.push_back(fmt::format("trajectory {}: {}", i, p.failure));
      continue;
    }
    r.pred.push_back(pick(p.path, times.grid));
    r.pred_at.push_back(pick(p.path, times.horizons));
    if (energy) r.pred_energy.row(i) = energy(r.pred.back()).transpose();
    if (learned.hamiltonian)
      r.learned_h.row(i) = learned.hamiltonian(Batch(r.pred.back())).transpose();
  }
}

}  // namespace

LearnedField learned_field(const nn::DynamicsModel<double>& model) {
  LearnedField learned{
      .field = [&model](double, const Batch& x, Batch& dxdt) { dxdt = model.field(x); }};
  // What the learned motion conserves: an HNN's H, an LNN's energy, a mass HNN's H, a CHNN's or
  // CLNN's kinetic plus learned potential energy.
  if (model.has_learned_energy())
    learned.hamiltonian = [&model](const Batch& x) -> Eigen::VectorXd {
      return model.learned_energy(x).col(0);
    };
  return learned;
}

Rollouts make_rollouts(const physics::System& truth, const nn::DynamicsModel<double>& model,
                       const Batch& x0, const RolloutConfig& config) {
  return make_rollouts(truth, learned_field(model), x0, config);
}

Rollouts make_rollouts(const physics::System& truth, const LearnedField& learned, const Batch& x0,
                       const RolloutConfig& config) {
  Rollouts r;
  r.t = physics::linspace(0.0, config.t_end, config.points);
  r.horizons = config.horizons;
  const Times times = merge_times(r.t, config.horizons);
  const Eigen::Index n = x0.rows(), m = Eigen::Index(r.t.size());
  r.true_energy.setConstant(n, m, NAN);
  r.pred_energy.setConstant(n, m, NAN);
  if (learned.hamiltonian) r.learned_h.setConstant(n, m, NAN);
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> normal;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd path =
        integrate_one(truth.field(), x0.row(i), times.all, config, nullptr);
    r.truth.push_back(pick(path, times.grid));
    r.truth_at.push_back(pick(path, times.horizons));
    r.true_energy.row(i) = truth.energy_batch(Batch(r.truth.back())).transpose();
    if (config.perturbation > 0) {
      Eigen::RowVectorXd start = x0.row(i);
      for (Eigen::Index c = 0; c < start.size(); ++c) {
        const double scale =
            config.perturbation_scale.empty() ? 1.0 : config.perturbation_scale[std::size_t(c)];
        start(c) += config.perturbation * scale * normal(rng);
      }
      const Eigen::MatrixXd moved = integrate_one(truth.field(), start, times.all, config, nullptr);
      r.floor.push_back(pick(moved, times.grid));
      r.floor_at.push_back(pick(moved, times.horizons));
    }
  }
  add_learned(r, learned, x0, times, config, [&](const Eigen::MatrixXd& states) {
    return Eigen::VectorXd(truth.energy_batch(Batch(states)));
  });
  return r;
}

Rollouts follow_measured(const std::vector<Eigen::MatrixXd>& measured, const LearnedField& learned,
                         const RolloutConfig& config) {
  Rollouts r;
  r.measured = true;
  r.t = physics::linspace(0.0, config.t_end, config.points);
  // Measurements exist at the grid's times only: each horizon moves to the nearest of them.
  for (double h : config.horizons) {
    const auto k = std::size_t(std::lround(h / config.t_end * (config.points - 1)));
    r.horizons.push_back(r.t[std::min(k, r.t.size() - 1)]);
  }
  const Times times = merge_times(r.t, r.horizons);
  const Eigen::Index n = Eigen::Index(measured.size()), m = Eigen::Index(r.t.size());
  r.true_energy.setConstant(n, m, NAN);
  r.pred_energy.setConstant(n, m, NAN);
  if (learned.hamiltonian) r.learned_h.setConstant(n, m, NAN);
  Batch starts(n, measured.empty() ? 0 : measured.front().cols());
  for (const Eigen::MatrixXd& path : measured) {
    HNN_TASKS_CHECK(path.rows() == m && path.row(0).allFinite(),
                    "follow_measured: a path of {} rows for {} times, or without its start",
                    path.rows(), m);
    starts.row(Eigen::Index(r.truth.size())) = path.row(0);
    r.truth.push_back(path);
    r.truth_at.push_back(pick(path, times.horizons));
  }
  add_learned(r, learned, starts, times, config, nullptr);
  return r;
}

}  // namespace hnn::tasks
