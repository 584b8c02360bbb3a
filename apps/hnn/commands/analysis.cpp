// The subcommands of what an HNN makes possible: `hnn bump` (Figure 5's energy bump on a pixel
// run), `hnn animate` (Figure 4: truth, baseline and HNN side by side as GIF and PNG) and
// `hnn reversibility` (forward-then-backward integration of any run's learned field).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "physics/integrator.h"
#include "tasks/experiments/pixel_pendulum.h"
#include "tasks/pixel/bump.h"
#include "tasks/run.h"
#include "tasks/studies/reproduce.h"

namespace hnn::app {

namespace {

// These commands evaluate small batches: OpenMP threads in Eigen's products would mostly wait.
void single_threaded() { Eigen::setNbThreads(1); }

void add_bump_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "bump", "Pixel pendulum: raise the learned H along its Riemann gradient (Figure 5)");
  auto dir = std::make_shared<std::string>();
  auto o = std::make_shared<tasks::pixel::BumpOptions>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("run", *dir, "Run folder of `hnn train pixel-pendulum --model hnn`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--trajectory", o->trajectory,
                  "Test trial whose first pair starts it (-1: the one at the 25th percentile of H)")
      ->check(CLI::Range(-1, 1000000))
      ->capture_default_str();
  cmd->add_option("--before", o->before, "Frames along S_H before the bump")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--raise", o->raise,
                  "Rise of the learned H along R_H, as a fraction of its spread over the test "
                  "trials (negative: lower it along -R_H)")
      ->capture_default_str();
  cmd->add_option("--riemann", o->riemann,
                  "Instead of --raise: this long along R_H (negative: along -R_H)");
  cmd->add_option("--after", o->after, "Frames along S_H after the bump")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--dt", o->dt, "Output spacing in frames")
      ->check(positive_real())
      ->capture_default_str();
  cmd->add_option("--out", *out, "Folder for bump.csv, bump.gif, bump_strip.png (default RUN)");
  cmd->callback([=] {
    single_threaded();
    tasks::pixel::BumpOptions options = *o;
    options.out = out->empty() ? std::filesystem::path(*dir) : std::filesystem::path(*out);
    const tasks::LoadedRun run = tasks::load_run(*dir);
    const tasks::pixel::PixelParts parts = tasks::pixel_parts(*run.run);
    const tasks::pixel::BumpResult r =
        tasks::pixel::energy_bump(parts.model, parts.data, parts.config, options);
    fmt::print(
        "hnn bump: test trial {}, {:.3g} time units along R_H: learned H {:.4g} -> {:.4g}; "
        "energy from frames {:.4g} -> {:.4g}; amplitude {:.3f} -> {:.3f} rad\n",
        r.trajectory, r.riemann_time, r.h_before, r.h_after, r.energy_before, r.energy_after,
        r.amplitude_before, r.amplitude_after);
    for (const auto& f : r.files) fmt::print("  {}\n", f.string());
  });
}

void add_animate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "animate", "Pixel pendulum: truth, baseline and HNN rollouts as GIF and PNG (Figure 4)");
  auto baseline = std::make_shared<std::string>(), hnn = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto trajectories = std::make_shared<int>(2), stride = std::make_shared<int>(10);
  cmd->add_option("baseline", *baseline, "Baseline run folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("hnn", *hnn, "HNN run folder (same seed)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", *out,
                  "Folder for rollout.gif and rollout_strip.png (default: the "
                  "HNN run's parent)");
  cmd->add_option("--trajectories", *trajectories, "Rows of the GIF")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  cmd->add_option("--stride", *stride, "Frames between strip images")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->callback([=] {
    single_threaded();
    const std::filesystem::path dir =
        out->empty() ? std::filesystem::path(*hnn).lexically_normal().parent_path()
                     : std::filesystem::path(*out);
    const tasks::LoadedRun base_run = tasks::load_run(*baseline), hnn_run = tasks::load_run(*hnn);
    tasks::pixel::write_comparison(tasks::pixel_parts(*base_run.run),
                                   tasks::pixel_parts(*hnn_run.run), dir, *trajectories, *stride);
    fmt::print("hnn animate: {} and {}\n", (dir / "rollout.gif").string(),
               (dir / "rollout_strip.png").string());
  });
}

void add_reversibility_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "reversibility", "Integrate learned fields forward and back: how far do they return?");
  auto runs = std::make_shared<std::vector<std::string>>();
  auto report = std::make_shared<std::string>();
  auto o = std::make_shared<tasks::ReversibilityOptions>();
  auto data = std::make_shared<std::string>();
  cmd->add_option("runs", *runs, "Run folders")->check(CLI::ExistingDirectory);
  cmd->add_option("--data", *data,
                  "The run's own data file at a new place (one run folder; a file whose SHA-256 "
                  "differs from the run's is refused)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--report", *report,
                  "A results folder of `hnn reproduce`: every run, and reversibility.md")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--integrators", o->integrators,
                  fmt::format("Comma-separated integrators, of {}",
                              fmt::join(physics::integrator_names(), ", ")))
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--t-end", o->t_end, "Span (default: the task's rollout span)")
      ->check(positive_real());
  cmd->add_option("--dt", o->dt, "Step of fixed-step methods (default span / 1000)")
      ->check(positive_real());
  cmd->add_option("--trajectories", o->trajectories, "Initial states")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->callback([=] {
    single_threaded();
    if (runs->empty() && report->empty()) {
      throw CLI::ValidationError("reversibility", "give run folders or --report RESULTS");
    }
    if (!data->empty() && (runs->size() != 1 || !report->empty())) {
      throw CLI::ValidationError("--data", "names the data file of one run folder");
    }
    for (const std::string& run : *runs) {
      fmt::print("{}\n", tasks::reversibility(run, *o, *data).dump(2));
    }
    if (!report->empty()) {
      tasks::reversibility_report(*report, *o);
      fmt::print("hnn reversibility: {}/reversibility.md\n", *report);
    }
  });
}

}  // namespace

void add_analysis_commands(CLI::App& app) {
  add_bump_command(app);
  add_animate_command(app);
  add_reversibility_command(app);
}

}  // namespace hnn::app
