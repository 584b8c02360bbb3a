// `hnn sweep SPEC --out DIR`: checks and expands the spec (apps/hnn/sweep/spec.cpp), then runs it
// through the sweep engine (apps/hnn/sweep/launch.cpp: the folder's lock, DIR/plan.json, the
// Python driver apps/hnn/sweep/sweep_driver.py and Dask distributed).

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "apps/hnn/sweep/launch.h"
#include "apps/hnn/sweep/spec.h"

namespace hnn::app {

namespace {

namespace fs = std::filesystem;

struct SweepOptions {
  std::string spec, out, emit;
  sweep::LaunchOptions launch;
  bool collect = false, list = false;
};

void run_sweep(const SweepOptions& o) {
  const fs::path out = fs::absolute(o.out).lexically_normal();
  const sweep::SweepPlan plan =
      sweep::expand(sweep::read_spec(o.spec), fmt::format("sweep spec {}", o.spec), out);
  if (o.list) return sweep::list_runs(plan, o.launch, out);
  sweep::check_scheduler(o.launch.scheduler);
  const std::string mode = o.collect ? "collect" : !o.emit.empty() ? "emit-" + o.emit : "run";
  sweep::launch(plan, o.launch, out, fs::absolute(o.spec).lexically_normal().string(), mode);
}

}  // namespace

void add_sweep_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sweep",
      "Train a grid of runs (a JSON or YAML spec) through Dask, on this machine or a "
      "cluster; see docs/sweeps.md");
  auto o = std::make_shared<SweepOptions>();
  cmd->add_option("spec", o->spec,
                  "Spec file: hnn train's option names, each with a list of values")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Sweep folder: runs/, plan.json, results.csv and .json")
      ->required();
  sweep::add_launch_options(*cmd, o->launch);
  cmd->add_flag("--collect", o->collect,
                "Only gather the finished runs into results.csv/.json (after --emit slurm)");
  cmd->add_option("--emit", o->emit, "Write DIR/sweep.slurm, a Slurm job array of the runs")
      ->check(CLI::IsMember({"slurm"}));
  cmd->add_flag("--list", o->list, "Print each run's hnn train command; run nothing");
  cmd->callback([o] { run_sweep(*o); });
}

}  // namespace hnn::app
