// `hnn export`: a trained run's learned H (and its gradient, so the field) as a self-contained C
// source file or a JSON file of the weights, written atomically.

#include "nn/export.h"

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "nn/atomic_file.h"
#include "nn/export.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

struct ExportOptions {
  std::string run, format, out, data;
};

void run_export(const ExportOptions& o) {
  const nn::ExportFormat format = nn::parse_export_format(o.format);
  const tasks::LoadedRun loaded = tasks::load_run(o.run, o.data);
  const std::unique_ptr<nn::DynamicsModel<double>> in_data_units =
      loaded.run->model_in_data_units();
  const nn::DynamicsModel<double>& model = *in_data_units;
  const std::string source =
      fmt::format("run {} (task {}, seed {})", o.run, loaded.task->name(), loaded.settings.seed);
  nn::write_file_atomic(o.out, nn::export_model(model, format, source));
  fmt::print("hnn export: {} as {} -> {}\n", model.describe(), o.format, o.out);
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Export a trained HNN's H as C source or JSON");
  auto o = std::make_shared<ExportOptions>();
  cmd->add_option("run", o->run, "Run folder written by `hnn train`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--format", o->format, "c or json")->required();
  cmd->add_option("--out", o->out, "The file to write")->required();
  cmd->add_option("--data", o->data,
                  "The run's own data file at a new place (measured-data runs: the data set the "
                  "units; a file whose SHA-256 differs from the run's is refused)")
      ->check(CLI::ExistingFile);
  cmd->callback([o] { run_export(*o); });
}

}  // namespace hnn::app
