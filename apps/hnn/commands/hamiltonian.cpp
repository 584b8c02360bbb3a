// `hnn hamiltonian`: a trained run's learned H (and the true energy where the run knows its H)
// on a 2-D slice of its state space, as CSV (tasks/hamiltonian_grid.h): the learned H of any
// number of degrees of freedom, for contours (scripts/plot.py --runs) or your own plots.

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "tasks/hamiltonian_grid.h"

namespace hnn::app {

void add_hamiltonian_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "hamiltonian",
      "A run's learned H (and the true energy) on a 2-D slice of state space, as CSV");
  auto dir = std::make_shared<std::string>();
  auto o = std::make_shared<tasks::HamiltonianGridCommand>();
  cmd->add_option("run", *dir, "Run folder of an hnn, dhnn or lnn model (a baseline learns no H)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--grid", o->grid,
                  "The two state columns of the slice and their ranges, e.g. x=-2:2,px=-2:2 "
                  "(the run's column names, or x_0..x_{d-1}; a data run: in its file's units)")
      ->required()
      ->option_text("A=LO:HI,B=LO:HI");
  cmd->add_option("--at", o->at,
                  "The value of every other state column on the slice, e.g. y=0,py=0")
      ->option_text("NAME=V,...");
  cmd->add_option("--points", o->points, "Grid points per axis")
      ->check(integer_in(2, 1000))
      ->capture_default_str();
  cmd->add_option("--data", o->data_file, "The run's data file, when it has moved")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "CSV file (default RUN/h_grid_A_B.csv)");
  cmd->callback([dir, o] {
    const tasks::HamiltonianGridWritten written = tasks::write_hamiltonian_grid(*dir, *o);
    fmt::print("hnn hamiltonian: {} points of the learned H{} -> {}\n", written.rows,
               written.truth ? " and the true energy" : " (the run knows no true H)",
               written.path.string());
  });
}

}  // namespace hnn::app
