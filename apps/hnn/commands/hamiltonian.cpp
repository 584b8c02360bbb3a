// `hnn hamiltonian`: a trained run's learned H, and the true energy where the run knows its H
// (TaskRun::learned_h, true_energy), on a 2-D slice of its state space (tasks/data/state_slice.h),
// as CSV: the learned H of any number of degrees of freedom, for contours (scripts/plot.py --runs
// draws them, scripts/charts/h_slice.py) or your own plots.
//
//   <axis A>,<axis B>,<the held columns, in state order>,learned_h,energy
//
// One row per grid point, axis A varying fastest; energy is an empty cell where the run knows
// no H. The learned H is as learned: defined only up to a constant.

#include <fmt/format.h>

#include <algorithm>
#include <functional>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "tasks/data/state_slice.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/run_folder.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

struct HamiltonianGridOptions {
  std::string grid{};           ///< "A=LO:HI,B=LO:HI"
  std::string at{};             ///< "C=V,...": every other state column
  int points = 60;              ///< per axis
  std::string data_file{};      ///< the run's data file at a new place (load_run)
  std::filesystem::path out{};  ///< default RUN/h_grid_A_B.csv
};

struct GridWritten {
  std::filesystem::path path;
  long rows = 0;
  bool truth = false;  ///< whether the energy column has values
};

// Rows evaluated at once: a 1000 x 1000 grid through a wide model would otherwise hold
// gigabytes of activations.
constexpr Eigen::Index kGridRows = 4096;

Eigen::VectorXd in_chunks(const physics::Batch& x,
                          const std::function<Eigen::VectorXd(const physics::Batch&)>& f) {
  Eigen::VectorXd out(x.rows());
  for (Eigen::Index start = 0; start < x.rows(); start += kGridRows) {
    const Eigen::Index n = std::min(kGridRows, x.rows() - start);
    const Eigen::VectorXd part = f(x.middleRows(start, n));
    if (part.size() == 0) return {};  // no true H
    out.segment(start, n) = part;
  }
  return out;
}

std::string grid_csv(const tasks::StateSlice& slice, const std::vector<std::string>& names,
                     const physics::Batch& x, const Eigen::VectorXd& learned,
                     const Eigen::VectorXd& energy) {
  std::vector<Eigen::Index> order = {slice.axes[0].column, slice.axes[1].column};
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    if (c != order[0] && c != order[1]) order.push_back(c);
  std::string csv;
  for (const Eigen::Index c : order) csv += names[std::size_t(c)] + ",";
  csv += "learned_h,energy\n";
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (const Eigen::Index c : order) csv += tasks::csv_cell(x(i, c)) + ",";
    csv += tasks::csv_cell(learned(i)) + "," + (energy.size() ? tasks::csv_cell(energy(i)) : "") +
           "\n";
  }
  return csv;
}

GridWritten write_grid(const std::filesystem::path& run_dir,
                       const HamiltonianGridOptions& command) {
  const tasks::LoadedRun loaded = tasks::load_run(run_dir, command.data_file);
  const tasks::TaskRun& run = *loaded.run;
  const std::vector<std::string> names = run.state_names();
  run.learned_h(physics::Batch::Zero(1, Eigen::Index(names.size())));  // a baseline: Error
  const tasks::StateSlice slice =
      tasks::parse_state_slice(command.grid, command.at, command.points, names);
  const physics::Batch x = tasks::slice_states(slice);
  const Eigen::VectorXd learned = in_chunks(x, [&](const auto& b) { return run.learned_h(b); });
  const Eigen::VectorXd energy = in_chunks(x, [&](const auto& b) { return run.true_energy(b); });
  const std::filesystem::path path =
      command.out.empty()
          ? run_dir / fmt::format("h_grid_{}_{}.csv", names[std::size_t(slice.axes[0].column)],
                                  names[std::size_t(slice.axes[1].column)])
          : command.out;
  tasks::RunFolder(path.parent_path().empty() ? "." : path.parent_path())
      .write_text(path.filename().string(), grid_csv(slice, names, x, learned, energy));
  return {.path = path, .rows = long(x.rows()), .truth = energy.size() > 0};
}

}  // namespace

void add_hamiltonian_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "hamiltonian",
      "A run's learned H (and the true energy) on a 2-D slice of state space, as CSV");
  auto dir = std::make_shared<std::string>();
  auto o = std::make_shared<HamiltonianGridOptions>();
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
    const GridWritten written = write_grid(*dir, *o);
    fmt::print("hnn hamiltonian: {} points of the learned H{} -> {}\n", written.rows,
               written.truth ? " and the true energy" : " (the run knows no true H)",
               written.path.string());
  });
}

}  // namespace hnn::app
