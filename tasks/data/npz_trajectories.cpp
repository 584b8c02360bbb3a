// An .npz of trajectories, as simulators and the HNN/LNN codes save them: states shaped
// (trajectories, times, components) with their times shaped (times,) or (trajectories, times),
// read into the table's rows (one per trajectory and time) and columns.
#include <fmt/format.h>

#include <algorithm>

#include "tasks/data/reader_util.h"
#include "tasks/error.h"

namespace hnn::tasks::reader {

namespace {

const NumpyArray* time_array(const NamedArrays& arrays) {
  for (const char* name : {"t", "time", "times"}) {
    for (const auto& [n, array] : arrays)
      if (n == name) return &array;
  }
  return nullptr;
}

// One array's columns over the n x m rows (trajectory-major).
Eigen::MatrixXd spread(const std::string& where, const NumpyArray& a, std::size_t n,
                       std::size_t m) {
  const auto& s = a.shape;
  const auto rows = Eigen::Index(n * m);
  if (s.size() == 3 && s[0] == n && s[1] == m) return a.columns;
  Eigen::MatrixXd out(rows, 1);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const std::size_t i = std::size_t(r) / m, j = std::size_t(r) % m;
    if (s.size() == 2 && s[0] == n && s[1] == m) {
      out(r, 0) = a.columns(Eigen::Index(i), Eigen::Index(j));
    } else if (s.size() == 1 && s[0] == m) {
      out(r, 0) = a.columns(Eigen::Index(j), 0);  // the times, the same for every trajectory
    } else if (s.size() == 1 && s[0] == n) {
      out(r, 0) = a.columns(Eigen::Index(i), 0);  // one value per trajectory
    } else {
      throw Error(fmt::format(
          "{}: shape {} does not fit {} trajectories of {} times (arrays of an archive of "
          "trajectories are {}x{}xK states, {}x{} or {} times, or {} values per trajectory)",
          where, shape_text(s), n, m, n, m, n, m, m, n));
    }
  }
  return out;
}

}  // namespace

std::optional<std::pair<std::size_t, std::size_t>> trajectory_shape(const NamedArrays& arrays) {
  for (const auto& [name, array] : arrays) {
    if (array.shape.size() == 3) return std::pair(array.shape[0], array.shape[1]);
  }
  const NumpyArray* time = time_array(arrays);
  if (time == nullptr) return std::nullopt;
  if (time->shape.size() == 2) return std::pair(time->shape[0], time->shape[1]);
  const std::size_t m = time->shape[0];
  for (const auto& [name, array] : arrays) {
    if (array.shape.size() == 2 && array.shape[1] == m && array.shape[0] != m)
      return std::pair(array.shape[0], m);
  }
  return std::nullopt;
}

void trajectory_columns(const NamedArrays& arrays, std::pair<std::size_t, std::size_t> shape,
                        Table& table) {
  const auto [n, m] = shape;
  std::vector<Eigen::MatrixXd> blocks;
  bool has_id = false;
  for (const auto& [name, array] : arrays) {
    blocks.push_back(spread(fmt::format("{}: array '{}'", table.source, name), array, n, m));
    for (Eigen::Index j = 0; j < blocks.back().cols(); ++j)
      table.names.push_back(array.shape.size() == 3 ? fmt::format("{}[{}]", name, j) : name);
    has_id |= name == "trajectory";
  }
  if (!has_id) {
    table.names.push_back("trajectory");
    Eigen::MatrixXd id(Eigen::Index(n * m), 1);
    for (Eigen::Index r = 0; r < id.rows(); ++r) id(r, 0) = double(std::size_t(r) / m);
    blocks.push_back(id);
  }
  table.values.resize(Eigen::Index(n * m), Eigen::Index(table.names.size()));
  Eigen::Index column = 0;
  for (const Eigen::MatrixXd& block : blocks) {
    table.values.middleCols(column, block.cols()) = block;
    column += block.cols();
  }
}

}  // namespace hnn::tasks::reader
