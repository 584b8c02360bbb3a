#pragma once
// The data files that ship with hnn (data/ in the source tree, share/hnn/data when installed).

#include <string>

namespace hnn::tasks {

/// The shipped copy of data/<relative>: $HNN_DATA_DIR if set, else the source tree's data/ (a
/// build), else the installed copy.
std::string default_data_path(const std::string& relative);

}  // namespace hnn::tasks
