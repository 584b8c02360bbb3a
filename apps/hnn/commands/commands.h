#pragma once
// The subcommands of the hnn program; each registers its options on the CLI11 app.

#include <CLI/CLI.hpp>

namespace hnn::app {

void add_train_command(CLI::App& app);
void add_evaluate_command(CLI::App& app);
void add_rollout_command(CLI::App& app);
void add_reproduce_command(CLI::App& app);
/// bump and animate (the pixel pendulum's Figures 5 and 4) and reversibility (any run):
/// apps/hnn/commands/analysis.cpp.
void add_analysis_commands(CLI::App& app);
/// simulate: trajectories of a Hamiltonian given as an expression (apps/hnn/commands/simulate.cpp).
void add_simulate_command(CLI::App& app);
/// export: a trained HNN's H as C source or JSON (apps/hnn/commands/export.cpp).
void add_export_command(CLI::App& app);
/// hamiltonian: a run's learned H on a 2-D slice of state space
/// (apps/hnn/commands/hamiltonian.cpp).
void add_hamiltonian_command(CLI::App& app);
/// sweep: a grid of runs from a spec file, through Dask (apps/hnn/sweep/command.cpp).
void add_sweep_command(CLI::App& app);
/// compare: the model families on a study's tasks beside the peers' published numbers, through
/// the sweep engine (apps/hnn/compare/command.cpp); argv is kept for the report.
void add_compare_command(CLI::App& app, int argc, char** argv);

}  // namespace hnn::app
