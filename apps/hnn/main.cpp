// hnn: train, evaluate and roll out Hamiltonian Neural Networks on the paper's tasks, and
// reproduce its Table 1. Every command lives in apps/hnn/commands/, apps/hnn/sweep/ or
// apps/hnn/compare/; every error is one line on stderr and a non-zero exit.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#if defined(__SSE3__)
#include <pmmintrin.h>
#endif

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/help_format.h"
#include "nn/atomic_file.h"

namespace {

// Note [Denormals flushed]: late in a float training run, products of saturated tanh units'
// derivatives and small gradients fall below float's normal range (1.2e-38), and every
// operation on such a number takes a microcode assist: the spring's float step in
// hnn_train_step went from 1.5 ms to 3.6 ms on average after about 3,000 steps (4,000 steps:
// 13.6 s of wall time, 6.0 s with denormals flushed, the same final loss to the last bit). The
// command line flushes them to zero (FTZ and DAZ) on its main thread before any work; the
// engine's threads, started later, inherit the setting.
void flush_denormals() {
#if defined(__SSE3__)
  _mm_setcsr(_mm_getcsr() | _MM_FLUSH_ZERO_ON | _MM_DENORMALS_ZERO_ON);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  flush_denormals();
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
