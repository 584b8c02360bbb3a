#pragma once
// Measured trajectories split into training and test data: the Dataset every field task trains
// on, plus what evaluating without a known H needs (each held-out stretch's own times and
// states, to roll out from its first state and compare).

#include <array>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tasks/data/dataset.h"
#include "tasks/data/measured_trajectories.h"

namespace hnn::tasks {

enum class SplitBy {
  kAuto,          ///< by trajectories when there are several, else by time
  kTrajectories,  ///< the last trajectories (in order of first appearance) are the test set
  kTime,          ///< the last rows of every trajectory are the test set
};
/// SplitBy's names, read both ways through nn/enum_names.h by the layers above (which link nn/;
/// this one does not, so the table is spelled as the nn::NameTable it is).
inline constexpr std::array<std::pair<SplitBy, std::string_view>, 3> kSplitByNames{{
    {SplitBy::kAuto, "auto"},
    {SplitBy::kTrajectories, "trajectories"},
    {SplitBy::kTime, "time"},
}};

struct SplitChoice {
  SplitBy by = SplitBy::kAuto;
  double test_fraction = 0.2;  ///< of the trajectories, or of each trajectory's rows; in (0, 1)
};

/// One stretch of a trajectory without a gap (held out, or for training through an integrator).
struct HeldOut {
  double trajectory = 0;  ///< its trajectory id
  std::string where;      ///< its first row: "FILE:LINE" or "FILE: row R"
  Eigen::VectorXd t;
  Batch x;
};

struct MeasuredData {
  Dataset data;                          ///< rows in trajectory, then time order
  std::vector<HeldOut> held_out;         ///< every test stretch of at least 2 points
  std::vector<HeldOut> train_stretches;  ///< the same of the training rows (rollout losses)
  std::string source;                    ///< the file
  std::vector<std::string> state_names;  ///< coordinates, then momenta (or velocities)
  Eigen::Index coordinates = 0;
  bool velocities = false;                    ///< the momenta are velocities: unit masses assumed
  bool derivatives_given = false;             ///< else dx/dt by finite differences
  bool derivatives_by_name = false;           ///< the columns found by name, not chosen
  std::vector<std::string> derivative_names;  ///< the columns of dx/dt, when given
  std::string derivatives_note;               ///< some derivative columns found, not all
  SplitBy split = SplitBy::kTime;             ///< the split made (never kAuto)
  /// Scattered states (no time column): split by rows, the file's last are the test set; no
  /// trajectories, no held-out or training stretches.
  bool scattered = false;
  int trajectories = 0, test_trajectories = 0, gaps = 0;
  Eigen::Index dropped_rows = 0;
};

/// Splits by whole trajectories (the last round(fraction * n) of them, at least one on each
/// side) or by time (the last round(fraction * m) rows of each trajectory of m rows, at least
/// one on each side); scattered states by rows (the last round(fraction * m) of the file's m,
/// with split auto only). dx/dt were computed before the split, so the rows next to the cut use
/// their neighbours across it. Throws tasks::Error on a fraction outside (0, 1) or a split by
/// trajectories of a file with one.
MeasuredData split_trajectories(const MeasuredTrajectories& trajectories, const SplitChoice& split);

struct MeasuredDataOptions {
  ColumnChoice columns;
  SplitChoice split{};
};

/// read_table, select_trajectories, split_trajectories.
MeasuredData load_measured_data(const std::string& path, const MeasuredDataOptions& options = {});

/// What was made of the file, in a few lines for the run to print: the state's columns, whether
/// they are velocities (unit masses assumed), where dx/dt came from, gaps and dropped rows,
/// the split.
std::string describe(const MeasuredData& data);

/// Where dx/dt came from, in one line for stderr: the columns (and whether found by name), or
/// finite differences and why.
std::string derivatives_source(const MeasuredData& data);

}  // namespace hnn::tasks
