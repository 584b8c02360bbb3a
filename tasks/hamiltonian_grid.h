#pragma once
// `hnn hamiltonian`: a run's learned H, and the true energy where the run knows its H, on a 2-D
// slice of its state space (tasks/data/state_slice.h), as CSV: what scripts/plot.py --runs draws
// as contours for systems of more than one degree of freedom.
//
//   <axis A>,<axis B>,<the held columns, in state order>,learned_h,energy
//
// One row per grid point, axis A varying fastest; energy is an empty cell where the run knows
// no H. The learned H is as learned: defined only up to a constant.

#include <filesystem>
#include <string>

namespace hnn::tasks {

struct HamiltonianGridCommand {
  std::string grid{};           ///< "A=LO:HI,B=LO:HI"
  std::string at{};             ///< "C=V,...": every other state column
  int points = 60;              ///< per axis
  std::string data_file{};      ///< the run's data file at a new place (load_run)
  std::filesystem::path out{};  ///< default RUN/h_grid_A_B.csv
};

struct HamiltonianGridWritten {
  std::filesystem::path path;
  long rows = 0;
  bool truth = false;  ///< whether the energy column has values
};

/// Loads the run, checks that its model learns an H (else Error: a baseline has none) and the
/// slice against its state columns, and writes the CSV atomically.
HamiltonianGridWritten write_hamiltonian_grid(const std::filesystem::path& run_dir,
                                              const HamiltonianGridCommand& command);

}  // namespace hnn::tasks
