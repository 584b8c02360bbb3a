// `hnn rollout`: integrate a trained model (and the true system) from test initial states with
// any integrator, and write the trajectories as CSV.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "physics/integrator.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

struct RolloutOptions {
  std::string run, out;
  tasks::RolloutRequest request;
};

}  // namespace

void add_rollout_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("rollout", "Roll out a trained model and the true system");
  auto o = std::make_shared<RolloutOptions>();
  cmd->add_option("run", o->run, "Run folder written by `hnn train`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--integrator", o->request.integrator,
                  fmt::format("One of {}", fmt::join(physics::integrator_names(), ", ")))
      ->capture_default_str();
  cmd->add_option("--dt", o->request.dt, "Step of fixed-step integrators")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--rtol", o->request.rtol, "Tolerance of dopri5")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--t-end", o->request.t_end,
                  "Time span (default: the task's rollout span; pixel-pendulum: --points frames)")
      ->check(positive_real());
  cmd->add_option("--points", o->request.points, "Output times")
      ->check(integer_in(2, 1000000))
      ->capture_default_str();
  cmd->add_option("--trajectories", o->request.trajectories, "Initial states (test states)")
      ->check(integer_in(1, 100000))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "CSV file (default RUN/rollout_INTEGRATOR.csv)");
  cmd->callback([o] {
    const std::filesystem::path out = tasks::write_rollout(o->run, o->request, o->out);
    fmt::print("hnn rollout: {} trajectories, {} -> {}\n", o->request.trajectories,
               o->request.integrator, out.string());
  });
}

}  // namespace hnn::app
