// The table: locating rows and columns for messages and choices, picking a reader by the file's
// extension, and the checks every reader shares.
#include "tasks/data/table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "tasks/data/reader_util.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace fs = std::filesystem;

namespace {

bool all_digits(const std::string& text) {
  return !text.empty() &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::string joined_names(const std::vector<std::string>& names) {
  constexpr std::size_t kShown = 12;  // a wide file would otherwise give a screen-long line
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < kShown; ++i) {
    text += (i ? ", " : "") + names[i];
  }
  if (names.size() > kShown) text += fmt::format(", ... ({} in all)", names.size());
  return text;
}

std::string lowercase_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

std::string Table::where(Eigen::Index row) const {
  if (!lines.empty()) return fmt::format("{}:{}", source, lines[std::size_t(row)]);
  return fmt::format("{}: row {}", source, row);
}

Eigen::Index Table::find(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : Eigen::Index(it - names.begin());
}

Eigen::Index Table::column(const std::string& name_or_index) const {
  if (const Eigen::Index j = find(name_or_index); j >= 0) return j;
  if (all_digits(name_or_index)) {
    const std::string& text = name_or_index;
    unsigned long index = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), index);
    HNN_TASKS_CHECK(ec == std::errc() && index < std::size_t(columns()),
                    "{}: no column {} (the file has {} columns, numbered from 0: {})", source, text,
                    columns(), joined_names(names));
    return Eigen::Index(index);
  }
  throw Error(
      fmt::format("{}: no column '{}' (columns: {})", source, name_or_index, joined_names(names)));
}

std::vector<Eigen::Index> Table::columns_of(const std::string& name_or_index) const {
  if (format == TableFormat::kNpz && find(name_or_index) < 0) {
    std::vector<Eigen::Index> parts;
    for (Eigen::Index k = 0; find(fmt::format("{}[{}]", name_or_index, k)) >= 0; ++k) {
      parts.push_back(find(fmt::format("{}[{}]", name_or_index, k)));
    }
    if (!parts.empty()) return parts;
  }
  return {column(name_or_index)};
}

Table read_table(const std::string& path) {
  reader::check_readable(path);
  const std::string ext = lowercase_extension(path);
  if (ext == ".csv") return read_csv(path);
  if (ext == ".npy") return read_npy(path);
  if (ext == ".npz") return read_npz(path);
  if (ext == ".txt") return read_lipson(path);
  throw Error(fmt::format(
      "{}: unknown file type '{}' (known: .csv with a header row, .npy, .npz, and .txt in the "
      "Schmidt & Lipson format)",
      path, ext));
}

namespace reader {

std::string shape_text(const std::vector<std::size_t>& shape) {
  std::string text;
  for (std::size_t d : shape) text += (text.empty() ? "" : "x") + std::to_string(d);
  return shape.empty() ? "a scalar" : text;
}

void check_readable(const std::string& path) {
  std::error_code ec;
  HNN_TASKS_CHECK(fs::exists(path, ec), "{}: no such file", path);
  HNN_TASKS_CHECK(!fs::is_directory(path, ec), "{}: is a directory, not a data file", path);
  HNN_TASKS_CHECK(std::ifstream(path, std::ios::binary).good(),
                  "{}: cannot open the file for reading", path);
}

std::string read_bytes(const std::string& path) {
  check_readable(path);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  HNN_TASKS_CHECK(!in.bad(), "{}: read error", path);
  return bytes;
}

void check_unique_names(const std::vector<std::string>& names, const std::string& where) {
  for (std::size_t j = 0; j < names.size(); ++j) {
    HNN_TASKS_CHECK(!names[j].empty(), "{}: column {} has no name", where, j);
    for (std::size_t k = 0; k < j; ++k) {
      HNN_TASKS_CHECK(names[k] != names[j], "{}: column '{}' appears twice (columns {} and {})",
                      where, names[j], k, j);
    }
  }
}

double parse_finite(const std::string& text, const std::string& where, const std::string& what) {
  double value = 0.0;
  const char* begin = text.data() + (!text.empty() && text[0] == '+' ? 1 : 0);
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  HNN_TASKS_CHECK(!(ec == std::errc::result_out_of_range && ptr == end),
                  "{}: {}: '{}' is out of the range of a double", where, what, text);
  HNN_TASKS_CHECK(ec == std::errc() && ptr == end && !text.empty(), "{}: {}: '{}' is not a number",
                  where, what, text);
  HNN_TASKS_CHECK(std::isfinite(value), "{}: {}: '{}' is not finite", where, what, text);
  return value;
}

}  // namespace reader

}  // namespace hnn::tasks
