// Your own system, end to end, through the installed package: the Hénon–Heiles Hamiltonian
// (a system the paper lacks) written in C++ with the autodiff engine's ops. AutodiffSystem gives
// its exact field by reverse mode; DOPRI5 simulates bounded trajectories (energies below the
// escape energy 1/6); an HNN and a baseline learn dx/dt from them; both are rolled out from
// held-out states against the true system. Exits 1 unless the HNN's energy MSE is the lower.

#include <autodiff/ops.h>
#include <fmt/format.h>
#include <nn/hnn.h>
#include <physics/autodiff/autodiff_system.h>
#include <physics/integrator.h>
#include <tasks/evaluate/energy_errors.h>
#include <tasks/evaluate/loss_stats.h>
#include <tasks/evaluate/rollouts.h>
#include <tasks/field/field_model_run.h>
#include <tasks/field/field_task.h>

#include <chrono>
#include <random>
#include <tuple>
#include <utility>

namespace ad = hnn::ad;
namespace nn = hnn::nn;
namespace physics = hnn::physics;
namespace tasks = hnn::tasks;
using V = ad::Var<double>;

// H = (px^2 + py^2)/2 + (x^2 + y^2)/2 + x^2 y - y^3/3, q = (x, y), p = (px, py); one row per state.
V henon_heiles(const V& q, const V& p) {
  const V x = ad::slice_cols(q, 0, 1), y = ad::slice_cols(q, 1, 1);
  return 0.5 * ad::sum_cols(ad::square(p) + ad::square(q)) + ad::square(x) * y -
         ad::square(y) * y / 3.0;
}

// `trajectories` states from the system's sampler, integrated over [0, t_end]; the states at
// `points` evenly spaced times (trajectory by trajectory) with their exact dx/dt.
std::pair<physics::Batch, physics::Batch> simulate(const physics::System& system, int trajectories,
                                                   double t_end, int points, std::mt19937_64& rng) {
  const auto dopri5 = physics::make_integrator("dopri5", {.rtol = 1e-10, .atol = 1e-12});
  const physics::Batch x0 = system.sample_initial_states(trajectories, rng);
  const physics::Batch x =
      dopri5->integrate(system.field(), x0, physics::linspace(0.0, t_end, points)).stacked();
  physics::Batch dxdt;
  system.vector_field(x, dxdt);
  return {x, dxdt};
}

int main() {
  const auto start = std::chrono::steady_clock::now();
  // Every state in |x|, |y|, |px|, |py| <= 1/2 with 0.02 <= H <= 0.12: inside the triangle of the
  // potential, where the motion stays bounded (regular and chaotic orbits both occur).
  physics::BoxSampling sampling;
  sampling.box.assign(4, physics::ValueRange{-0.5, 0.5});
  sampling.energy = physics::ValueRange{0.02, 0.12};
  const physics::AutodiffSystem system("henon-heiles", 2, henon_heiles, sampling);

  std::mt19937_64 rng(17);
  tasks::Dataset data;
  std::tie(data.train_x, data.train_dxdt) = simulate(system, 25, 10.0, 40, rng);
  std::tie(data.test_x, data.test_dxdt) = simulate(system, 25, 10.0, 40, rng);
  const physics::Batch rollout_states = system.sample_initial_states(10, rng);  // held out
  const tasks::RolloutConfig rollouts{.trajectories = 10, .t_end = 50.0, .points = 200};
  fmt::print(
      "{}: {} train and {} test states from 25 + 25 trajectories; rollouts of {} held-out "
      "states to t = {}\n\n",
      system.name(), data.train_x.rows(), data.test_x.rows(), rollout_states.rows(),
      rollouts.t_end);

  const tasks::TrainConfig train{.steps = 1500, .batch_size = 0, .learning_rate = 1e-3};
  fmt::print("{:<9} {:>22} {:>22} {:>8} {:>8}\n", "model", "test loss", "energy MSE", "failed",
             "train s");
  double energy_mse[2] = {0, 0};
  for (const nn::ModelKind kind : {nn::ModelKind::kHnn, nn::ModelKind::kBaseline}) {
    std::mt19937_64 init(1);
    const auto model = nn::make_model<double>({.model = kind, .dim = 4, .hidden = {64, 64}}, init);
    const tasks::TrainResult result = tasks::train_model(*model, data, train, 2, {.quiet = true});
    const nn::MeanStderr loss = tasks::loss_stats(*model, data.test_x, data.test_dxdt);
    const tasks::Rollouts r = tasks::make_rollouts(system, *model, rollout_states, rollouts);
    const nn::MeanStderr energy = tasks::energy_mse(r);
    long failed = 0;
    for (const bool f : r.failed) failed += f;
    energy_mse[kind == nn::ModelKind::kHnn ? 0 : 1] = energy.mean;
    fmt::print("{:<9} {:>12.3e} ± {:<7.1e} {:>12.3e} ± {:<7.1e} {:>8} {:>8.2f}\n", model->name(),
               loss.mean, loss.std_error, energy.mean, energy.std_error, failed, result.seconds);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("\nwall time {:.1f} s\n", wall);
  if (!(energy_mse[0] < energy_mse[1])) {
    fmt::print("FAILED: the HNN's energy MSE ({:.3e}) is not below the baseline's ({:.3e})\n",
               energy_mse[0], energy_mse[1]);
    return 1;
  }
  fmt::print("the HNN's energy MSE is {:.0f}x below the baseline's\n",
             energy_mse[1] / energy_mse[0]);
  return 0;
}
