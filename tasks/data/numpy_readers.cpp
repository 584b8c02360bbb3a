// The NumPy readers: xtensor parses each .npy array (header and data), libzip opens .npz
// archives. The header is parsed and checked (dtype, rank, size against the bytes present)
// before xtensor allocates the data, so a corrupt shape cannot ask for terabytes.
#include <zip.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <regex>
#include <sstream>
#include <xtensor/xnpy.hpp>

#include "tasks/data/reader_util.h"
#include "tasks/data/table.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

using Array = reader::NumpyArray;

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::size_t> shape;
  std::size_t data_offset = 0;
};

// The header's length field (little endian, 2 bytes in format 1.x, 4 in 2.x and 3.x), read here
// only to check that the header and the data fit in the bytes present.
std::size_t header_length(const std::string& bytes, int width) {
  std::size_t length = 0;
  for (int k = width - 1; k >= 0; --k)
    length = length * 256 + static_cast<unsigned char>(bytes[8 + k]);
  return length;
}

// The header dictionary as NumPy writes it, padded with spaces to a line.
const std::regex& numpy_header_layout() {
  static const std::regex layout(
      R"(\{'descr': *'[<>|=][a-zA-Z][0-9]*', *'fortran_order': *(True|False), *)"
      R"('shape': *\(( *[0-9]+ *,)* *([0-9]+ *)?\), *\} *\n?)");
  return layout;
}

NpyHeader read_npy_header(const std::string& bytes, const std::string& where) {
  HNN_TASKS_CHECK(bytes.size() >= 10 && bytes.compare(0, 6, "\x93NUMPY") == 0,
                  "{}: not a NumPy .npy array (it does not start with \\x93NUMPY)", where);
  const int width = bytes[6] == 1 ? 2 : 4;
  const std::size_t length = header_length(bytes, width);
  HNN_TASKS_CHECK(length > 0 && 8 + width + length <= bytes.size(),
                  "{}: truncated: the .npy header claims {} bytes but the file has {}", where,
                  length, bytes.size());
  NpyHeader header;
  header.data_offset = 8 + std::size_t(width) + length;
  // xtensor's parser trusts the header's layout (an empty field is undefined behaviour there,
  // found by fuzz/table_fuzz.cpp): only NumPy's own layout reaches it.
  HNN_TASKS_CHECK(std::regex_match(bytes.substr(8 + width, length), numpy_header_layout()),
                  "{}: not a readable .npy header (not NumPy's {{'descr': ..., 'fortran_order': "
                  "..., 'shape': (...), }} layout)",
                  where);
  try {
    xt::detail::parse_header(bytes.substr(8 + width, length), header.descr, &header.fortran_order,
                             header.shape);
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: not a readable .npy header: {}", where, e.what()));
  }
  return header;
}

// The ranks an array may have: a .npy file's is a table (rows x columns); an .npz member is a
// column, columns, or trajectories x times x components.
struct Ranks {
  std::size_t min, max;
};
constexpr Ranks kNpyRanks{2, 2}, kNpzRanks{1, 3};

// Checks the dtype, rank and size before any allocation; returns the bytes per value.
std::size_t check_npy_header(const NpyHeader& h, const std::string& bytes, const std::string& where,
                             Ranks ranks) {
  HNN_TASKS_CHECK(h.descr == "<f8" || h.descr == "<f4",
                  "{}: holds '{}' values; only float64 ('<f8') and float32 ('<f4') are read", where,
                  h.descr);
  HNN_TASKS_CHECK(
      h.shape.size() >= ranks.min && h.shape.size() <= ranks.max, "{}: an array of shape {}; {}{}",
      where, reader::shape_text(h.shape),
      ranks.max == 2 ? "a 2-D array (rows x columns) is needed"
                     : "a 1-D, 2-D or 3-D array (trajectories x times x components) is needed",
      h.shape.size() == 3 ? " (trajectories x times x components need their times: save them "
                            "in an .npz, numpy.savez(FILE, x=x, t=t))"
                          : "");
  const std::size_t word = h.descr == "<f8" ? 8 : 4;
  std::size_t expected = word;
  for (std::size_t d : h.shape) {
    HNN_TASKS_CHECK(d == 0 || expected <= bytes.size() / d,
                    "{}: truncated: shape {} needs more bytes than the file's {}", where,
                    reader::shape_text(h.shape), bytes.size());
    expected *= d;
  }
  const std::size_t present = bytes.size() - h.data_offset;
  HNN_TASKS_CHECK(present == expected,
                  "{}: {}: shape {} of '{}' needs {} bytes of data, but {} follow the header",
                  where, present < expected ? "truncated" : "trailing bytes",
                  reader::shape_text(h.shape), h.descr, expected, present);
  HNN_TASKS_CHECK(std::find(h.shape.begin(), h.shape.end(), std::size_t{0}) == h.shape.end(),
                  "{}: an empty array (shape {})", where, reader::shape_text(h.shape));
  return word;
}

// The array as rows x its last axis: a 1-D array is one column, a 3-D one (n, m, k) has row
// i * m + j for [i, j, :].
template <typename T>
Eigen::MatrixXd to_columns(xt::detail::npy_file&& file, const std::vector<std::size_t>& shape) {
  const auto array = std::move(file).cast<T>();
  const std::size_t inner = shape.size() == 3 ? shape[1] : 1;
  const auto rows = Eigen::Index(shape[0] * inner);
  const auto cols = Eigen::Index(shape.size() >= 2 ? shape.back() : 1);
  Eigen::MatrixXd out(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const std::size_t a = std::size_t(i) / inner, b = std::size_t(i) % inner;
    for (Eigen::Index j = 0; j < cols; ++j) {
      const auto c = std::size_t(j);
      out(i, j) = double(shape.size() == 3   ? array(a, b, c)
                         : shape.size() == 2 ? array(a, c)
                                             : array(a));
    }
  }
  return out;
}

void check_finite(const Array& a, const std::string& where) {
  for (Eigen::Index j = 0; j < a.columns.cols(); ++j) {
    for (Eigen::Index i = 0; i < a.columns.rows(); ++i) {
      const double v = a.columns(i, j);
      if (std::isfinite(v)) continue;
      if (a.shape.size() == 1)
        throw Error(fmt::format("{}, row {}: {} is not finite", where, i, v));
      if (a.shape.size() == 3) {
        throw Error(fmt::format("{}, [{}, {}, {}]: {} is not finite", where,
                                std::size_t(i) / a.shape[1], std::size_t(i) % a.shape[1], j, v));
      }
      throw Error(fmt::format("{}, row {}, column {}: {} is not finite", where, i, j, v));
    }
  }
}

// `where` names the file, or the file and the npz member.
Array parse_npy(const std::string& bytes, const std::string& where, Ranks ranks) {
  const NpyHeader header = read_npy_header(bytes, where);
  const std::size_t word = check_npy_header(header, bytes, where, ranks);
  std::istringstream in(bytes);
  Array array{header.shape, {}};
  try {
    xt::detail::npy_file file = xt::detail::load_npy_file(in);
    array.columns = word == 8 ? to_columns<double>(std::move(file), header.shape)
                              : to_columns<float>(std::move(file), header.shape);
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: not a readable .npy array: {}", where, e.what()));
  }
  check_finite(array, where);
  return array;
}

struct ZipCloser {
  void operator()(zip_t* archive) const { zip_discard(archive); }
};
using ZipArchive = std::unique_ptr<zip_t, ZipCloser>;

ZipArchive open_zip(const std::string& path) {
  int code = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_RDONLY, &code);
  if (archive == nullptr) {
    zip_error_t error;
    zip_error_init_with_code(&error, code);
    const std::string reason = zip_error_strerror(&error);
    zip_error_fini(&error);
    throw Error(fmt::format("{}: not a readable .npz archive (libzip: {})", path, reason));
  }
  return ZipArchive(archive);
}

std::string read_member(zip_t* archive, zip_uint64_t index, const zip_stat_t& stat,
                        std::uintmax_t archive_bytes, const std::string& where) {
  std::unique_ptr<zip_file_t, decltype(&zip_fclose)> file(zip_fopen_index(archive, index, 0),
                                                          &zip_fclose);
  HNN_TASKS_CHECK(file != nullptr, "{}: cannot open it in the archive (libzip: {})", where,
                  zip_strerror(archive));
  // A member's size is the archive's claim: deflate expands at most 1032:1, so a larger claim
  // (a damaged or hostile archive, found by fuzz/table_fuzz.cpp) is refused before allocating.
  constexpr zip_uint64_t kMaxRatio = 1032, kSlack = 1024;
  HNN_TASKS_CHECK((stat.valid & ZIP_STAT_SIZE) && (stat.valid & ZIP_STAT_COMP_SIZE) &&
                      stat.comp_size <= archive_bytes &&
                      stat.size <= kMaxRatio * stat.comp_size + kSlack,
                  "{}: the archive claims {} bytes from {} compressed: not a readable member",
                  where, stat.size, stat.comp_size);
  std::string bytes;
  try {
    bytes.resize(stat.size);
  } catch (const std::exception&) {
    throw Error(
        fmt::format("{}: claims {} bytes, more than this machine can hold", where, stat.size));
  }
  const zip_int64_t got = zip_fread(file.get(), bytes.data(), stat.size);
  HNN_TASKS_CHECK(got >= 0 && zip_uint64_t(got) == stat.size,
                  "{}: cannot read it from the archive (libzip: {})", where,
                  zip_file_strerror(file.get()));
  return bytes;
}

// Adds a member's columns: "x" for a 1-D array, "x[0]", "x[1]", ... for a 2-D one.
void add_columns(Table& table, const std::string& name, const Array& array,
                 std::vector<Eigen::MatrixXd>& blocks, std::string& first) {
  if (!blocks.empty()) {
    HNN_TASKS_CHECK(array.columns.rows() == blocks[0].rows(),
                    "{}: array '{}' has {} rows but array '{}' has {} (the arrays are the columns "
                    "of one table and need one length)",
                    table.source, name, array.columns.rows(), first, blocks[0].rows());
  } else {
    first = name;
  }
  for (Eigen::Index j = 0; j < array.columns.cols(); ++j) {
    table.names.push_back(array.shape.size() == 1 ? name : fmt::format("{}[{}]", name, j));
  }
  blocks.push_back(array.columns);
}

}  // namespace

Table read_npy(const std::string& path) {
  const Array array = parse_npy(reader::read_bytes(path), path, kNpyRanks);
  Table table{path, TableFormat::kNpy, {}, {}, {}, {}};
  for (Eigen::Index j = 0; j < array.columns.cols(); ++j) table.names.push_back(std::to_string(j));
  table.values = array.columns;
  return table;
}

Table read_npz(const std::string& path) {
  reader::check_readable(path);
  const ZipArchive archive = open_zip(path);
  const std::uintmax_t archive_bytes = std::filesystem::file_size(path);
  std::vector<std::pair<std::string, Array>> arrays;
  const zip_int64_t entries = zip_get_num_entries(archive.get(), 0);
  for (zip_int64_t i = 0; i < entries; ++i) {
    zip_stat_t stat;
    HNN_TASKS_CHECK(zip_stat_index(archive.get(), zip_uint64_t(i), 0, &stat) == 0,
                    "{}: member {} is unreadable (libzip: {})", path, i,
                    zip_strerror(archive.get()));
    const std::string member = stat.name;
    if (!member.empty() && member.back() == '/') continue;  // a folder entry
    HNN_TASKS_CHECK(member.size() > 4 && member.ends_with(".npy"),
                    "{}: member '{}' is not a .npy array (an .npz holds name.npy members)", path,
                    member);
    const std::string name = member.substr(0, member.size() - 4);
    const std::string where = fmt::format("{}: array '{}'", path, name);
    arrays.emplace_back(
        name, parse_npy(read_member(archive.get(), zip_uint64_t(i), stat, archive_bytes, where),
                        where, kNpzRanks));
  }
  HNN_TASKS_CHECK(!arrays.empty(), "{}: the archive holds no arrays", path);
  Table table{path, TableFormat::kNpz, {}, {}, {}, {}};
  if (const auto shape = reader::trajectory_shape(arrays)) {
    reader::trajectory_columns(arrays, *shape, table);
  } else {
    std::vector<Eigen::MatrixXd> blocks;
    std::string first;
    for (const auto& [name, array] : arrays) add_columns(table, name, array, blocks, first);
    table.values.resize(blocks[0].rows(), Eigen::Index(table.names.size()));
    Eigen::Index column = 0;
    for (const Eigen::MatrixXd& block : blocks) {
      table.values.middleCols(column, block.cols()) = block;
      column += block.cols();
    }
  }
  reader::check_unique_names(table.names, path);
  return table;
}

}  // namespace hnn::tasks
