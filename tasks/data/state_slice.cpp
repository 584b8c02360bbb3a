#include "tasks/data/state_slice.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "tasks/data/initial_states.h"
#include "tasks/data/reader_util.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// An item "NAME=VALUE" of `option`: the state column it names (known, not named before) and
// the text after '='.
std::pair<Eigen::Index, std::string> named_item(const std::string& item, const std::string& option,
                                                const std::string& form,
                                                const std::vector<std::string>& names,
                                                std::vector<bool>& named) {
  const std::size_t eq = item.find('=');
  HNN_TASKS_CHECK(eq != std::string::npos && eq > 0, "{}: '{}' is not {}", option, item, form);
  const std::string name = item.substr(0, eq);
  const Eigen::Index c = state_column(name, names);
  HNN_TASKS_CHECK(c >= 0, "{}: '{}' is not a state column; the run's are {}", option, name,
                  known_columns(names));
  HNN_TASKS_CHECK(!named[std::size_t(c)],
                  "{}: state column '{}' is named twice (--grid and --at "
                  "together name each column once)",
                  option, names[std::size_t(c)]);
  named[std::size_t(c)] = true;
  return {c, item.substr(eq + 1)};
}

SliceAxis parse_axis(const std::string& item, const std::vector<std::string>& names,
                     std::vector<bool>& named) {
  const auto [c, range] = named_item(item, "--grid", "NAME=LO:HI", names, named);
  const std::size_t colon = range.find(':');
  const std::string where = fmt::format("--grid '{}'", item);
  HNN_TASKS_CHECK(colon != std::string::npos, "{}: the range is not LO:HI (e.g. {}=-2:2)", where,
                  names[std::size_t(c)]);
  SliceAxis axis{.column = c,
                 .lo = reader::parse_finite(range.substr(0, colon), where, "LO"),
                 .hi = reader::parse_finite(range.substr(colon + 1), where, "HI")};
  HNN_TASKS_CHECK(axis.lo < axis.hi, "{}: LO must be below HI", where);
  return axis;
}

}  // namespace

StateSlice parse_state_slice(const std::string& grid, const std::string& at, int points,
                             const std::vector<std::string>& names) {
  HNN_TASKS_CHECK(points >= 2 && points <= 1000, "--points {}: expected 2 to 1000 per axis",
                  points);
  const std::vector<std::string> items = split_values(grid);
  HNN_TASKS_CHECK(items.size() == 2,
                  "--grid '{}': expected two state columns NAME=LO:HI separated by a comma "
                  "(e.g. {}=-2:2,{}=-2:2)",
                  grid, names.front(), names[names.size() / 2]);
  std::vector<bool> named(names.size(), false);
  StateSlice slice{.held = Eigen::RowVectorXd::Constant(Eigen::Index(names.size()), NAN),
                   .points = points};
  for (std::size_t k = 0; k < 2; ++k) slice.axes[k] = parse_axis(items[k], names, named);
  if (!at.empty()) {
    for (const std::string& item : split_values(at)) {
      const auto [c, value] = named_item(item, "--at", "NAME=VALUE", names, named);
      slice.held(c) = reader::parse_finite(value, fmt::format("--at '{}'", item), "VALUE");
    }
  }
  std::vector<std::string> missing, example;
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (named[c]) continue;
    missing.push_back(names[c]);
    example.push_back(names[c] + "=V");
  }
  HNN_TASKS_CHECK(missing.empty(),
                  "--at: no value for {}: the slice holds every column off the grid at one "
                  "(--at {})",
                  fmt::join(missing, ", "), fmt::join(example, ","));
  return slice;
}

physics::Batch slice_states(const StateSlice& slice) {
  const Eigen::Index n = slice.points;
  const auto along = [n](const SliceAxis& a) { return Eigen::VectorXd::LinSpaced(n, a.lo, a.hi); };
  const Eigen::VectorXd first = along(slice.axes[0]), second = along(slice.axes[1]);
  physics::Batch x = slice.held.replicate(n * n, 1);
  for (Eigen::Index j = 0; j < n; ++j) {
    x.col(slice.axes[0].column).segment(j * n, n) = first;
    x.col(slice.axes[1].column).segment(j * n, n).setConstant(second(j));
  }
  return x;
}

}  // namespace hnn::tasks
