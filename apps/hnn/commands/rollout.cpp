// `hnn rollout`: integrate a trained model (and the true system, where the run knows it) from
// the run's test states or from given ones with any integrator, and write the trajectories as
// CSV (tasks/report/rollout_csv.h).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "physics/integrator.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

struct RolloutOptions {
  std::string run;
  tasks::RolloutCommand command;
  int trajectories = tasks::RolloutRequest::kDefaultTrajectories;
};

}  // namespace

void add_rollout_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "rollout", "Roll out a trained model (and the true system) from test states or your own");
  auto o = std::make_shared<RolloutOptions>();
  cmd->add_option("run", o->run, "Run folder written by `hnn train`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--integrator", o->command.request.integrator,
                  fmt::format("One of {}", fmt::join(physics::integrator_names(), ", ")))
      ->capture_default_str();
  cmd->add_option("--dt", o->command.request.dt, "Step of fixed-step integrators")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--rtol", o->command.request.rtol, "Tolerance of dopri5")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--t-end", o->command.request.t_end,
                  "Time span (default: the task's rollout span; pixel-pendulum: --points frames)")
      ->check(positive_real());
  cmd->add_option("--points", o->command.request.points, "Output times")
      ->check(integer_in(2, 1000000))
      ->capture_default_str();
  auto* trajectories =
      cmd->add_option("--trajectories", o->trajectories,
                      "How many test states to start from (at most as many as the run has)")
          ->check(integer_in(1, 100000))
          ->capture_default_str();
  auto* state = cmd->add_option("--state", o->command.states,
                                "An initial state 'v0,v1,...' in the run's state order (a data "
                                "run: its columns, in its units); repeat for more")
                    ->allow_extra_args(false)
                    ->excludes(trajectories);
  cmd->add_option("--states", o->command.states_file,
                  "CSV of initial states, one per row, its header naming the state columns (a "
                  "data run's own names, or x_0..x_{d-1})")
      ->excludes(trajectories)
      ->excludes(state);
  cmd->add_flag("--project", o->command.project,
                "Move the given states onto the system's constraints first (the constrained "
                "tasks: rods keep their lengths, velocities move along them); without it, a state "
                "off them is refused");
  cmd->add_option("--data", o->command.data_file, "The run's data file, when it has moved")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->command.out, "CSV file (default RUN/rollout_INTEGRATOR.csv)");
  cmd->callback([o, trajectories] {
    if (trajectories->count() > 0) o->command.request.trajectories = o->trajectories;
    const tasks::RolloutWritten written = tasks::write_rollout(o->run, o->command);
    for (const std::string& note : written.notes) fmt::print(stderr, "hnn rollout: {}\n", note);
    fmt::print("hnn rollout: {} {}, {} -> {}\n", written.trajectories,
               written.trajectories == 1 ? "trajectory" : "trajectories",
               o->command.request.integrator, written.path.string());
  });
}

}  // namespace hnn::app
