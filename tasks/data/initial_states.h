#pragma once
// Initial states a user gives `hnn rollout`: `--state v0,v1,...` on the command line, or a CSV
// file (`--states FILE`) whose header names the state's columns. Both are read against the
// run's state columns (TaskRun::state_names: the data's own names for a data run, x_0..x_{d-1}
// otherwise) into one state per row.

#include <string>
#include <vector>

#include "physics/types.h"

namespace hnn::tasks {

/// One state per value "v0,v1,...": as many numbers as `names`, in their order. Throws Error
/// naming the value, and the position and column of a bad number.
physics::Batch states_from_values(const std::vector<std::string>& values,
                                  const std::vector<std::string>& names);

/// One state per data row of the CSV file `path`, whose header names each state column once,
/// in any order, by its name in `names` or as x_0..x_{d-1}. Throws Error naming the file, and
/// the line and column of a bad cell or the header's unknown or missing column.
physics::Batch states_from_file(const std::string& path, const std::vector<std::string>& names);

/// The state column that `name` names, as `names[c]` or as x_c; -1 for none.
Eigen::Index state_column(const std::string& name, const std::vector<std::string>& names);

/// `text` split at its commas, without spaces or tabs: "1, 2" gives "1" and "2".
std::vector<std::string> split_values(const std::string& text);

/// "q, p (or x_0, x_1)": the names a state column may go by, for messages.
std::string known_columns(const std::vector<std::string>& names);

}  // namespace hnn::tasks
