// `hnn reproduce`: the paper's Table 1, baseline and HNN on every task.

#include "tasks/studies/reproduce.h"

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"

namespace hnn::app {

void add_reproduce_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("reproduce", "Train baseline and HNN on every task: Table 1");
  auto options = std::make_shared<tasks::ReproduceOptions>();
  auto dtype = std::make_shared<std::string>(), preset = std::make_shared<std::string>("paper");
  auto steps = std::make_shared<int>(0);
  cmd->add_option("--tasks", options->tasks, "Comma-separated tasks (default: all)")
      ->delimiter(',');
  cmd->add_option("--seeds", options->seeds, "Seeds per task and model (averaged)")
      ->check(positive_integer())
      ->capture_default_str();
  cmd->add_option("--dtype", *dtype, "float or double (default: each task's own)")
      ->check(CLI::IsMember(tasks::dtype_names()));
  cmd->add_option("--preset", *preset, "Model widths of every run: paper or lean")
      ->check(CLI::IsMember(tasks::preset_names()))
      ->capture_default_str();
  cmd->add_option("--jobs", options->jobs, "Runs trained at once")
      ->check(integer_in(1, 64))
      ->capture_default_str();
  cmd->add_option("--steps", *steps, "Override every task's step count (quick looks)")
      ->check(positive_integer());
  cmd->add_option("--out", options->out,
                  "Results folder (its run folders are replaced when run again)")
      ->capture_default_str();
  cmd->add_flag("!--no-reversibility", options->reversibility,
                "Skip the reversibility report (the table only, sooner)");
  cmd->callback([=] {
    tasks::ReproduceOptions o = *options;
    if (!dtype->empty()) o.dtype = tasks::parse_dtype(*dtype);
    o.preset = tasks::parse_preset(*preset);
    if (*steps > 0) o.steps = *steps;
    tasks::reproduce(o);
    fmt::print("hnn reproduce: {}\n", (o.out / "table1.md").string());
  });
}

}  // namespace hnn::app
