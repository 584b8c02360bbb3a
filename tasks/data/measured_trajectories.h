#pragma once
// From a table to trajectories: which columns are the state, the time and the trajectory id,
// the rows of each trajectory cut at gaps in time, and dx/dt at every row (given columns, or
// finite differences that never reach across a trajectory boundary or a gap).

#include <string>
#include <vector>

#include "physics/types.h"
#include "tasks/data/table.h"

namespace hnn::tasks {

using physics::Batch;

/// Which column is what. Each entry is a column name or a 0-based column index ("3"); an npz
/// 2-D array's name ("q") stands for all its columns. Empty entries take the defaults.
struct ColumnChoice {
  /// Defaults: in a Lipson file, the first half of the '%' header's columns; elsewhere none
  /// (they must be given).
  std::vector<std::string> coords = {};
  std::vector<std::string> momenta = {};  ///< conjugate momenta, one per coordinate
  /// Instead of momenta: dq/dt, taken as momenta with unit masses (the run should say so).
  /// Default in a Lipson file: the second half of the header's columns.
  std::vector<std::string> velocities = {};
  /// dx/dt of every state column in state order (coordinates, then momenta); empty: the
  /// columns named d<x>/dt, d<x>dt, d<x>_dt or <x>_dot (an .npz also d<x>) when the file has
  /// one for every state column, else finite differences of the samples; {"none"}: finite
  /// differences.
  std::vector<std::string> derivatives = {};
  std::string time = {};        ///< default: the column named "t", else "time", else "times"
  std::string trajectory = {};  ///< default: "trajectory", else "trial"; none: one trajectory
  /// A step longer than gap_factor times its trajectory's median step is a gap, where the
  /// trajectory is cut; 0 never cuts. Otherwise must be > 1.
  double gap_factor = 1.5;
};

/// A stretch of one trajectory without a gap, in time order.
struct Segment {
  double trajectory = 0;           ///< its trajectory id (0 when the file has none)
  std::vector<Eigen::Index> rows;  ///< the table's rows
  Eigen::VectorXd t;
  Batch x;  ///< (q, p) per row, p the velocities when those were given
  Batch dxdt;
};

struct MeasuredTrajectories {
  Table table;                                ///< what was read, for messages (Table::where)
  std::vector<std::string> state_names;       ///< coordinates, then momenta (or velocities)
  Eigen::Index coordinates = 0;               ///< n: the state is 2n wide
  bool velocities = false;                    ///< p holds velocities: unit masses assumed
  bool derivatives_given = false;             ///< dx/dt from columns, not differences
  bool derivatives_by_name = false;           ///< those columns found by their names
  std::vector<std::string> derivative_names;  ///< the columns of dx/dt, when given
  std::string derivatives_note;               ///< some derivative columns found but not all, or ""
  /// No time column: the rows are scattered states with their given dx/dt, in one segment
  /// without times; no trajectories.
  bool scattered = false;
  std::string time_name, trajectory_name;  ///< trajectory_name is "" when there is none
  std::vector<double> trajectory_ids;      ///< in order of first appearance
  std::vector<Segment> segments;           ///< by trajectory (that order), then time
  int gaps = 0;                            ///< cuts made at gaps in time
  /// Rows left out: stretches between gaps too short (< 3 points) to difference.
  Eigen::Index dropped_rows = 0;
};

/// Picks the columns, groups rows by trajectory id (rows of one id in file order), cuts at gaps
/// and computes dx/dt. A file without a time column whose derivative columns are given (by name
/// or chosen) holds scattered states (MeasuredTrajectories::scattered). Throws tasks::Error
/// naming the file (and line or row) on a missing, repeated or doubly chosen column,
/// coordinates and momenta of different counts, derivative columns not one per state column,
/// no time column without derivative columns (or with a trajectory column), a trajectory of
/// fewer than 3 points, time not increasing within a trajectory, or nothing left to
/// difference.
MeasuredTrajectories select_trajectories(Table table, const ColumnChoice& choice);

/// dx/dt at each of the times t (increasing, at least 3, possibly unevenly spaced) from the
/// three-point Lagrange formula: central inside, one-sided at both ends, exact for states
/// quadratic in t.
Batch finite_differences(const Eigen::VectorXd& t, const Batch& x);

}  // namespace hnn::tasks
