// The data task's options of `hnn train`: each one a key of the task's settings (metrics.json's
// "task_settings"), so a resumed or reloaded run reads its file the same way.

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"

namespace hnn::app {

std::function<void(nlohmann::json&, const std::string&)> add_data_options(CLI::App& cmd) {
  struct Values {
    std::vector<std::string> coords, momenta, velocities, derivatives;
    std::string time, trajectory, split, hamiltonian, loss, integrator;
    double test_fraction = 0, dt = 0;
    int horizon = 0;
  };
  auto v = std::make_shared<Values>();
  const char* group = "The data task (hnn train data --data FILE)";
  const auto list = [&](const char* name, std::vector<std::string>& into, const char* help) {
    cmd.add_option(name, into, help)->delimiter(',')->group(group);
  };
  list("--coords", v->coords, "Coordinate columns q (names or 0-based indices, comma-separated)");
  list("--momenta", v->momenta, "Momentum columns p, one per coordinate");
  list("--velocities", v->velocities,
       "Velocity columns dq/dt instead of momenta (unit masses assumed)");
  list("--derivatives", v->derivatives,
       "Columns of dx/dt, one per state column (default: finite differences)");
  cmd.add_option("--time", v->time, "Time column (default: t, else time)")->group(group);
  cmd.add_option("--trajectory", v->trajectory,
                 "Trajectory id column (default: trajectory, else trial; none: one trajectory)")
      ->group(group);
  cmd.add_option("--split", v->split, "Test split: auto, trajectories or time")
      ->check(CLI::IsMember({"auto", "trajectories", "time"}))
      ->group(group);
  cmd.add_option("--test-fraction", v->test_fraction,
                 "Share of the trajectories (or of each one's rows) held out (default 0.2)")
      ->check(CLI::Range(0.0, 1.0).description("in (0, 1)"))
      ->group(group);
  cmd.add_option("--hamiltonian", v->hamiltonian,
                 "A known H over the state's column names, for the energy metric")
      ->group(group);
  const char* training = "Training through an integrator (every task that learns a field)";
  cmd.add_option("--loss", v->loss,
                 "derivative (dx/dt targets, the default) or rollout (from states alone: the "
                 "model's field integrated over --horizon sampling intervals)")
      ->check(CLI::IsMember(loss_names()))
      ->group(training);
  cmd.add_option("--horizon", v->horizon, "Sampling intervals per rollout window (default 1)")
      ->check(CLI::Range(1, 1000))
      ->group(training);
  cmd.add_option("--integrator", v->integrator,
                 "The rollout loss's integrator: leapfrog, yoshida4, midpoint or rk4 (default)")
      ->check(CLI::IsMember({"leapfrog", "yoshida4", "midpoint", "rk4"}))
      ->group(training);
  cmd.add_option("--dt", v->dt,
                 "The rollout loss's step (default: the sampling interval; it must divide it)")
      ->check(positive_real())
      ->group(training);
  // Writes the options given into the task's settings; refuses them for another task.
  return [v, &cmd](nlohmann::json& settings, const std::string& task) {
    const auto put = [&](const char* option, const char* key, const nlohmann::json& value,
                         bool any_task = false) {
      if (cmd.get_option(option)->count() == 0) return;
      if (task != "data" && !any_task) {
        throw std::invalid_argument(
            fmt::format("{} applies to the data task only, not to '{}'", option, task));
      }
      settings[key] = value;
    };
    put("--coords", "coords", v->coords);
    put("--momenta", "momenta", v->momenta);
    put("--velocities", "velocities", v->velocities);
    put("--derivatives", "derivatives", v->derivatives);
    put("--time", "time", v->time);
    put("--trajectory", "trajectory", v->trajectory);
    put("--split", "split", v->split);
    put("--test-fraction", "test_fraction", v->test_fraction);
    put("--hamiltonian", "hamiltonian", v->hamiltonian);
    put("--loss", "loss", v->loss, true);
    put("--horizon", "horizon", v->horizon, true);
    put("--integrator", "integrator", v->integrator, true);
    put("--dt", "dt", v->dt, true);
  };
}

}  // namespace hnn::app
