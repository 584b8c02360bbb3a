// The text readers: CSV with a header row (comma-, semicolon- or tab-separated), and the Schmidt &
// Lipson format through physics::load_lipson (which already reads all its variants: '%o v' and '% x
// v' headers, extra trailing columns, CRLF, blank lines).
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <fstream>

#include "physics/lipson.h"
#include "physics/types.h"
#include "tasks/data/reader_util.h"
#include "tasks/data/table.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::string trimmed(const std::string& text) {
  const std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t") - begin + 1);
}

// Splits a line at `delimiter` outside double quotes; quotes are dropped and "" inside them is ".
std::vector<std::string> split_csv_line(const std::string& line, const std::string& where,
                                        char delimiter) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') {
      cells.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == delimiter && !quoted) {
      cells.emplace_back();
    } else {
      cells.back() += c;
    }
  }
  HNN_TASKS_CHECK(!quoted, "{}: a double quote is not closed", where);
  for (std::string& cell : cells) cell = trimmed(cell);
  return cells;
}

// The header's delimiter: a comma, else a semicolon or a tab when the header holds one
// (spreadsheets in locales with a decimal comma write ';').
char delimiter_of(const std::string& header) {
  for (const char c : {',', ';', '\t'}) {
    if (header.find(c) != std::string::npos) return c;
  }
  return ',';
}

// Refuses bytes no text CSV holds (NUL, as in a NumPy or zip file renamed .csv), naming what
// the file looks like when the start says so.
void check_text(std::istream& in, const std::string& path) {
  std::string head(4096, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  in.clear();
  in.seekg(0);
  if (head.find('\0') == std::string::npos) return;
  const char* looks = head.rfind("\x93NUMPY", 0) == 0 ? " (it is a NumPy array: name it .npy)"
                      : head.rfind("PK", 0) == 0      ? " (it is a zip archive, e.g. .npz or .xlsx)"
                                                      : "";
  throw Error(fmt::format("{}: not a text CSV: it holds binary bytes{}", path, looks));
}

// A header of numbers is a first data row: the columns have no names.
void check_header_names(const std::vector<std::string>& names, const std::string& where) {
  for (const std::string& name : names) {
    double value = 0;
    const char* begin = name.data() + (!name.empty() && (name[0] == '+') ? 1 : 0);
    const auto [end, ec] = std::from_chars(begin, name.data() + name.size(), value);
    if (name.empty() || ec != std::errc() || end != name.data() + name.size()) return;
  }
  throw Error(fmt::format(
      "{}: the first row must name the columns (it holds numbers: {}); add a header row such as "
      "t,q,p",
      where,
      fmt::join(names.begin(), names.begin() + long(std::min<std::size_t>(names.size(), 4)), ",")));
}

// The next line that is not blank, without its '\r' (and a UTF-8 byte-order mark on line 1,
// which spreadsheets write); false at the end of the file.
bool next_line(std::istream& in, std::string& text, int& line) {
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (line == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
    if (text.find_first_not_of(" \t") != std::string::npos) return true;
  }
  return false;
}

// A cell that is not a number: a hint when it holds another delimiter or a decimal comma.
std::string cell_hint(const std::string& cell, char delimiter) {
  if (delimiter != ';' && cell.find(';') != std::string::npos)
    return " (cells separated by ';'? then the header must be too)";
  if (delimiter != '\t' && cell.find('\t') != std::string::npos)
    return " (cells separated by tabs? then the header must be too)";
  if (delimiter != ',' && cell.find(',') != std::string::npos)
    return " (a decimal comma? write 0.5, not 0,5)";
  return "";
}

void read_csv_rows(std::istream& in, int& line, char delimiter, Table& table,
                   std::vector<double>& cells) {
  const std::size_t width = table.names.size();
  for (std::string text; next_line(in, text, line);) {
    const std::string where = fmt::format("{}:{}", table.source, line);
    const std::vector<std::string> row = split_csv_line(text, where, delimiter);
    HNN_TASKS_CHECK(row.size() == width, "{}: {} cells where the header names {} columns{}", where,
                    row.size(), width, row.size() == 1 ? cell_hint(row[0], delimiter) : "");
    for (std::size_t j = 0; j < width; ++j) {
      try {
        cells.push_back(
            reader::parse_finite(row[j], where, fmt::format("column '{}'", table.names[j])));
      } catch (const Error& e) {
        throw Error(std::string(e.what()) + cell_hint(row[j], delimiter));
      }
    }
    table.lines.push_back(line);
  }
}

// "d<name>" for each header name when the extra columns are as many (the shipped files'
// derivatives), else the column's 0-based index in the file.
std::vector<std::string> lipson_names(const physics::LipsonData& data) {
  std::vector<std::string> names = {"trial", "t"};
  names.insert(names.end(), data.columns.begin(), data.columns.end());
  const std::size_t named = data.columns.size();
  const std::size_t extra = std::size_t(data.values.cols()) - named;
  for (std::size_t k = 0; k < extra; ++k) {
    names.push_back(extra == named ? "d" + data.columns[k] : std::to_string(names.size()));
  }
  return names;
}

}  // namespace

Table read_csv(const std::string& path) {
  reader::check_readable(path);
  std::ifstream in(path, std::ios::binary);
  check_text(in, path);
  Table table{path, TableFormat::kCsv, {}, {}, {}, {}};
  int line = 0;
  std::string text;
  HNN_TASKS_CHECK(next_line(in, text, line),
                  "{}: empty file (a header row naming the columns "
                  "is needed)",
                  path);
  const std::string header_where = fmt::format("{}:{}", path, line);
  const char delimiter = delimiter_of(text);
  table.names = split_csv_line(text, header_where, delimiter);
  check_header_names(table.names, header_where);
  reader::check_unique_names(table.names, header_where);
  std::vector<double> cells;
  read_csv_rows(in, line, delimiter, table, cells);
  HNN_TASKS_CHECK(!in.bad(), "{}:{}: read error", path, line);
  HNN_TASKS_CHECK(!table.lines.empty(), "{}: no data rows after the header", header_where);
  table.values = Eigen::Map<const RowMajor>(cells.data(), Eigen::Index(table.lines.size()),
                                            Eigen::Index(table.names.size()));
  return table;
}

Table read_lipson(const std::string& path) {
  reader::check_readable(path);
  physics::LipsonData data;
  try {
    data = physics::load_lipson(path);
  } catch (const physics::DataError& e) {
    throw Error(e.what());  // already "FILE:LINE: reason"
  }
  Table table{path, TableFormat::kLipson, {}, {}, {}, {}};
  table.names = lipson_names(data);
  table.header_state = data.columns;
  reader::check_unique_names(table.names, fmt::format("{}: the '%' header", path));
  table.values.resize(data.rows(), 2 + data.values.cols());
  table.values << data.trial.cast<double>(), data.t, data.values;
  table.lines.assign(data.line.data(), data.line.data() + data.line.size());
  return table;
}

}  // namespace hnn::tasks
