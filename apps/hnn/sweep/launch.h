#pragma once
// Running a checked plan of runs through the sweep engine: the folder's lock, the program's copy,
// DIR/plan.json, then the Python driver (apps/hnn/sweep/sweep_driver.py). Shared by `hnn sweep` and
// `hnn compare` (which adds its report to the plan).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/hnn/sweep/spec.h"

namespace CLI {
class App;
}  // namespace CLI

namespace hnn::app::sweep {

/// How the plan runs; the options of `hnn sweep` that are not the spec.
struct LaunchOptions {
  std::string scheduler;  // "": a local cluster
  int workers = 0;        // 0: one per threads_per_run cores
  int threads_per_run = 1;
  bool retry_failed = false;
};

/// Adds --scheduler, --workers, --threads-per-run and --retry-failed to `cmd`, into `o`.
void add_launch_options(CLI::App& cmd, LaunchOptions& o);

/// `text` as one shell word.
std::string shell_quote(const std::string& text);

/// Prints each run's `hnn train` command, as the driver would run it; writes nothing.
void list_runs(const SweepPlan& plan, const LaunchOptions& o, const std::filesystem::path& out);

/// A file that hnn installs into share/hnn: $`env` when set, share/hnn/`name` beside the installed
/// program, or else `source`, the source tree's.
std::filesystem::path shared_file(const char* env, const std::string& name,
                                  const std::filesystem::path& source);

/// Throws std::invalid_argument unless `scheduler` is empty or an address like tcp://HOST:8786.
void check_scheduler(const std::string& scheduler);

/// Creates `out`, takes its lock, copies this program and writes plan.json (the plan, `spec` as
/// its source, and `extra`'s keys beside them: "report_module", a Python file whose
/// write(plan, table) the driver calls after its table), then becomes the driver in `mode` (run,
/// collect, emit-slurm). Returns only by throwing.
[[noreturn]] void launch(const SweepPlan& plan, const LaunchOptions& o,
                         const std::filesystem::path& out, const std::string& spec,
                         const std::string& mode, const nlohmann::json& extra = {});

}  // namespace hnn::app::sweep
