#pragma once
// A number as a CSV cell of the files runs write (rollout.csv and the like).

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace hnn::tasks {

/// `digits` significant digits; an empty cell when v is NaN or infinite.
inline std::string csv_cell(double v, int digits = 12) {
  return std::isfinite(v) ? fmt::format("{:.{}g}", v, digits) : std::string();
}

}  // namespace hnn::tasks
