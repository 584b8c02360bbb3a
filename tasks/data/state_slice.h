#pragma once
// A 2-D slice of a run's state space, for `hnn hamiltonian`: two state columns on a grid
// (`--grid "x=-2:2,px=-2:2"`), every other column held at a value (`--at "y=0,py=0"`). Columns
// are named as `hnn rollout --states` names them: the run's own names, or x_0..x_{d-1}.

#include <array>
#include <string>
#include <vector>

#include "physics/types.h"

namespace hnn::tasks {

/// One axis of the grid: a state column and its range.
struct SliceAxis {
  Eigen::Index column = 0;
  double lo = 0.0, hi = 0.0;
};

struct StateSlice {
  std::array<SliceAxis, 2> axes{};
  /// Every state column's value where it is held (the axes' entries are unused).
  Eigen::RowVectorXd held{};
  int points = 0;  ///< per axis
};

/// The slice of `grid` ("A=LO:HI,B=LO:HI", two distinct columns, LO < HI) and `at` ("C=V,...",
/// every other column once) over the run's columns `names`, `points` per axis (2 to 1000).
/// Throws Error naming the option and the bad part: a malformed item, an unknown or repeated
/// column, an empty range, a held column left out.
StateSlice parse_state_slice(const std::string& grid, const std::string& at, int points,
                             const std::vector<std::string>& names);

/// The slice's states, points^2 rows: the first axis varies fastest.
physics::Batch slice_states(const StateSlice& slice);

}  // namespace hnn::tasks
