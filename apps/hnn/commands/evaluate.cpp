// `hnn evaluate`: the metrics of a run folder's saved parameters, again.

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "tasks/run.h"

namespace hnn::app {

void add_evaluate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("evaluate", "Evaluate the saved parameters of a run folder");
  auto dir = std::make_shared<std::string>();
  auto data = std::make_shared<std::string>();
  auto write = std::make_shared<bool>(false);
  cmd->add_option("run", *dir, "Run folder written by `hnn train`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--data", *data,
                  "Evaluate on this measured-data file instead of the run's own: another file "
                  "of the same format, or the run's own at a new place (its SHA-256 is not "
                  "checked)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--write", *write, "Also rewrite the run's rollout.csv and evaluation.json");
  cmd->callback([=] {
    const nlohmann::json m = tasks::evaluate_run(*dir, *data, *write);
    fmt::print("{}\n", m.dump(2));
  });
}

}  // namespace hnn::app
