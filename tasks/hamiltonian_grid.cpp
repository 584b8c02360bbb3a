#include "tasks/hamiltonian_grid.h"

#include <fmt/format.h>

#include <algorithm>

#include "tasks/data/state_slice.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/run_folder.h"
#include "tasks/run.h"

namespace hnn::tasks {

namespace {

// Rows evaluated at once: a 1000 x 1000 grid through a wide model would otherwise hold
// gigabytes of activations.
constexpr Eigen::Index kChunk = 4096;

Eigen::VectorXd in_chunks(const physics::Batch& x,
                          const std::function<Eigen::VectorXd(const physics::Batch&)>& f) {
  Eigen::VectorXd out(x.rows());
  for (Eigen::Index start = 0; start < x.rows(); start += kChunk) {
    const Eigen::Index n = std::min(kChunk, x.rows() - start);
    const Eigen::VectorXd part = f(x.middleRows(start, n));
    if (part.size() == 0) return {};  // no true H
    out.segment(start, n) = part;
  }
  return out;
}

std::string grid_csv(const StateSlice& slice, const std::vector<std::string>& names,
                     const physics::Batch& x, const Eigen::VectorXd& learned,
                     const Eigen::VectorXd& energy) {
  std::vector<Eigen::Index> order = {slice.axes[0].column, slice.axes[1].column};
  for (Eigen::Index c = 0; c < x.cols(); ++c)
    if (c != order[0] && c != order[1]) order.push_back(c);
  std::string csv;
  for (const Eigen::Index c : order) csv += names[std::size_t(c)] + ",";
  csv += "learned_h,energy\n";
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (const Eigen::Index c : order) csv += csv_cell(x(i, c)) + ",";
    csv += csv_cell(learned(i)) + "," + (energy.size() ? csv_cell(energy(i)) : "") + "\n";
  }
  return csv;
}

}  // namespace

HamiltonianGridWritten write_hamiltonian_grid(const std::filesystem::path& run_dir,
                                              const HamiltonianGridCommand& command) {
  const LoadedRun loaded = load_run(run_dir, command.data_file);
  const TaskRun& run = *loaded.run;
  const std::vector<std::string> names = run.state_names();
  run.learned_h(physics::Batch::Zero(1, Eigen::Index(names.size())));  // a baseline: Error
  const StateSlice slice = parse_state_slice(command.grid, command.at, command.points, names);
  const physics::Batch x = slice_states(slice);
  const Eigen::VectorXd learned = in_chunks(x, [&](const auto& b) { return run.learned_h(b); });
  const Eigen::VectorXd energy = in_chunks(x, [&](const auto& b) { return run.true_energy(b); });
  const std::filesystem::path path =
      command.out.empty()
          ? run_dir / fmt::format("h_grid_{}_{}.csv", names[std::size_t(slice.axes[0].column)],
                                  names[std::size_t(slice.axes[1].column)])
          : command.out;
  RunFolder(path.parent_path().empty() ? "." : path.parent_path())
      .write_text(path.filename().string(), grid_csv(slice, names, x, learned, energy));
  return {.path = path, .rows = long(x.rows()), .truth = energy.size() > 0};
}

}  // namespace hnn::tasks
