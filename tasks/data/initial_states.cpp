#include "tasks/data/initial_states.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "tasks/data/reader_util.h"
#include "tasks/data/table.h"
#include "tasks/error.h"

namespace hnn::tasks {

std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> parts(1);
  for (char c : text) {
    if (c == ',') {
      parts.emplace_back();
    } else if (c != ' ' && c != '\t') {
      parts.back() += c;
    }
  }
  return parts;
}

std::string known_columns(const std::vector<std::string>& names) {
  std::vector<std::string> numbered;
  for (std::size_t c = 0; c < names.size(); ++c) numbered.push_back(fmt::format("x_{}", c));
  if (numbered == names) return fmt::format("{}", fmt::join(names, ", "));
  return fmt::format("{} (or {})", fmt::join(names, ", "), fmt::join(numbered, ", "));
}

Eigen::Index state_column(const std::string& cell, const std::vector<std::string>& names) {
  for (std::size_t c = 0; c < names.size(); ++c)
    if (cell == names[c] || cell == fmt::format("x_{}", c)) return Eigen::Index(c);
  return -1;
}

physics::Batch states_from_values(const std::vector<std::string>& values,
                                  const std::vector<std::string>& names) {
  physics::Batch x(Eigen::Index(values.size()), Eigen::Index(names.size()));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string where = fmt::format("--state '{}'", values[i]);
    const std::vector<std::string> parts = split_values(values[i]);
    HNN_TASKS_CHECK(parts.size() == names.size(), "{}: {} numbers, and a state has {}: {}", where,
                    parts.size(), names.size(), fmt::join(names, ", "));
    for (std::size_t c = 0; c < parts.size(); ++c) {
      x(Eigen::Index(i), Eigen::Index(c)) =
          reader::parse_finite(parts[c], where, fmt::format("value {} ({})", c + 1, names[c]));
    }
  }
  return x;
}

physics::Batch states_from_file(const std::string& path, const std::vector<std::string>& names) {
  const Table table = read_csv(path);
  const std::string header = fmt::format("{}: header", path);
  std::vector<Eigen::Index> from(names.size(), -1);  // state column -> the file's
  for (Eigen::Index j = 0; j < table.columns(); ++j) {
    const std::string& cell = table.names[std::size_t(j)];
    const Eigen::Index c = state_column(cell, names);
    HNN_TASKS_CHECK(c >= 0, "{}: column '{}' is not a state column; the run's are {}", header, cell,
                    known_columns(names));
    HNN_TASKS_CHECK(from[std::size_t(c)] < 0,
                    "{}: columns '{}' and '{}' both name state column '{}'", header,
                    table.names[std::size_t(from[std::size_t(c)])], cell, names[std::size_t(c)]);
    from[std::size_t(c)] = j;
  }
  for (std::size_t c = 0; c < names.size(); ++c) {
    HNN_TASKS_CHECK(from[c] >= 0, "{}: no column '{}'; a state has {}", header, names[c],
                    known_columns(names));
  }
  physics::Batch x(table.rows(), Eigen::Index(names.size()));
  for (std::size_t c = 0; c < names.size(); ++c) x.col(Eigen::Index(c)) = table.values.col(from[c]);
  return x;
}

}  // namespace hnn::tasks
