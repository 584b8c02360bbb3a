// hnn: train, evaluate and roll out Hamiltonian Neural Networks on the paper's tasks, and
// reproduce its Table 1. Every command lives in apps/hnn/commands/, apps/hnn/sweep/ or
// apps/hnn/compare/; every error is one line on stderr and a non-zero exit.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/help_format.h"
#include "nn/atomic_file.h"

int main(int argc, char** argv) {
  CLI::App app{"hnn: Hamiltonian Neural Networks (Greydanus et al. 2019) in C++"};
  app.formatter(std::make_shared<hnn::app::HelpFormatter>());  // before the subcommands copy it
  app.set_version_flag("--version", "hnn " HNN_VERSION);
  app.require_subcommand(1);
  hnn::app::add_train_command(app);
  hnn::app::add_evaluate_command(app);
  hnn::app::add_rollout_command(app);
  hnn::app::add_reproduce_command(app);
  hnn::app::add_analysis_commands(app);
  hnn::app::add_simulate_command(app);
  hnn::app::add_export_command(app);
  hnn::app::add_hamiltonian_command(app);
  hnn::app::add_sweep_command(app);
  hnn::app::add_compare_command(app, argc, argv);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // already reported (a stopped training run)
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::string message = e.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    fmt::print(stderr, "hnn: error: {} (see --help)\n", message);
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {  // e.g. --out under a regular file
    fmt::print(stderr, "hnn: error: {}\n", hnn::nn::filesystem_error_line(e));
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "hnn: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
