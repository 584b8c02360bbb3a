#include "nn/parameter_file_format.h"

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>

namespace hnn::nn {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'H', 'N', 'N', 'P', 'A', 'R', 'A', 'M'};
constexpr std::uint32_t kMaxNameLength = 1u << 16;
constexpr std::uint32_t kMaxCount = 1u << 20;
constexpr std::uint64_t kMaxDim = std::uint64_t(1) << 31;

std::uint64_t fnv1a(const char* data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

// ---- writing ------------------------------------------------------------------------------

void put_uint(std::string& out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

void put_string(std::string& out, std::string_view s) {
  put_uint(out, s.size(), 4);
  out.append(s);
}

template <typename T>
void put_values(std::string& out, const Matrix<T>& m) {
  using Bits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
  if constexpr (std::endian::native == std::endian::little) {
    out.append(reinterpret_cast<const char*>(m.data()), sizeof(T) * std::size_t(m.size()));
  } else {
    for (Index i = 0; i < m.size(); ++i) put_uint(out, std::bit_cast<Bits>(m.data()[i]), sizeof(T));
  }
}

// ---- reading ------------------------------------------------------------------------------

std::string errno_text() { return std::strerror(errno); }

class Reader {
 public:
  Reader(const fs::path& path, const std::string& bytes) : path_(path), bytes_(bytes) {}

  std::uint64_t uint(int size, const char* what) {
    need(std::size_t(size), what);
    std::uint64_t value = 0;
    for (int i = 0; i < size; ++i) {
      value |= std::uint64_t(static_cast<unsigned char>(bytes_[pos_ + i])) << (8 * i);
    }
    pos_ += std::size_t(size);
    return value;
  }
  std::string_view take(std::size_t size, const char* what) {
    need(size, what);
    const std::string_view s(bytes_.data() + pos_, size);
    pos_ += size;
    return s;
  }
  void need(std::size_t size, const char* what) const {
    if (size > bytes_.size() - pos_) {
      throw ParameterFileError(path_, fmt::format("truncated: {} needs {} bytes at offset {} but "
                                                  "the file has {} bytes",
                                                  what, size, pos_, bytes_.size()));
    }
  }
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  const fs::path& path_;
  const std::string& bytes_;
  std::size_t pos_ = 0;
};

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParameterFileError(path, "cannot open for reading: " + errno_text());
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ParameterFileError(path, "read error: " + errno_text());
  return bytes;
}

// The header up to the parameter count; returns the size of one scalar.
std::size_t parse_header(const fs::path& path, Reader& r, ParameterFileInfo& info) {
  r.take(sizeof(kMagic), "the magic bytes");
  info.version = std::uint32_t(r.uint(4, "the format version"));
  if (info.version != kParameterFileVersion) {
    throw ParameterFileError(path, fmt::format("format version {}, but this build reads version {}",
                                               info.version, kParameterFileVersion));
  }
  const std::uint64_t scalar = r.uint(1, "the scalar type");
  if (scalar != std::uint64_t(ScalarType::kFloat32) &&
      scalar != std::uint64_t(ScalarType::kFloat64)) {
    throw ParameterFileError(path, fmt::format("unknown scalar type code {}", scalar));
  }
  info.scalar = ScalarType(scalar);
  if (r.uint(3, "the reserved bytes") != 0) {
    throw ParameterFileError(path, "reserved bytes not zero");
  }
  const std::uint64_t kind_length = r.uint(4, "the kind's length");
  if (kind_length > kMaxNameLength) {
    throw ParameterFileError(path, fmt::format("corrupt: kind length {}", kind_length));
  }
  info.kind = std::string(r.take(kind_length, "the kind"));
  return info.scalar == ScalarType::kFloat32 ? 4 : 8;
}

// One parameter's name and shape; skips its values and returns where they start.
std::size_t parse_entry(const fs::path& path, Reader& r, std::size_t scalar_size,
                        ParameterFileInfo::Entry& entry) {
  const std::uint64_t length = r.uint(4, "a parameter name's length");
  if (length > kMaxNameLength) {
    throw ParameterFileError(path, fmt::format("corrupt: parameter name length {}", length));
  }
  entry.name = std::string(r.take(length, "a parameter name"));
  const std::uint64_t rows = r.uint(8, "a parameter's row count");
  const std::uint64_t cols = r.uint(8, "a parameter's column count");
  // Checked before anything is allocated: a corrupt shape cannot ask for huge buffers.
  if (rows > kMaxDim || cols > kMaxDim) {
    throw ParameterFileError(
        path, fmt::format("corrupt: parameter '{}' is {}x{}", entry.name, rows, cols));
  }
  if (rows * cols > r.remaining() / scalar_size) {
    throw ParameterFileError(path, fmt::format("truncated: parameter '{}' is {}x{} but only {} "
                                               "bytes remain at offset {}",
                                               entry.name, rows, cols, r.remaining(), r.pos()));
  }
  entry.rows = Index(rows);
  entry.cols = Index(cols);
  const std::size_t offset = r.pos();
  r.take(std::size_t(rows * cols) * scalar_size, "parameter values");
  return offset;
}

}  // namespace

template <typename T>
std::string encode_parameter_file(std::string_view kind,
                                  const std::vector<NamedParameter<T>>& parameters) {
  std::string out(kMagic, sizeof(kMagic));
  put_uint(out, kParameterFileVersion, 4);
  put_uint(out, std::uint64_t(scalar_type_of<T>()), 1);
  put_uint(out, 0, 3);
  put_string(out, kind);
  put_uint(out, parameters.size(), 4);
  for (const NamedParameter<T>& p : parameters) {
    put_string(out, p.name);
    put_uint(out, std::uint64_t(p.var.rows()), 8);
    put_uint(out, std::uint64_t(p.var.cols()), 8);
    put_values<T>(out, p.var.value());
  }
  put_uint(out, fnv1a(out.data(), out.size()), 8);
  return out;
}

ParsedParameterFile parse_parameter_file(const fs::path& path) {
  if (fs::is_directory(path)) throw ParameterFileError(path, "is a directory, not a file");
  ParsedParameterFile parsed;
  parsed.bytes = read_file(path);
  const std::string& bytes = parsed.bytes;
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw ParameterFileError(path, "not an hnn parameter file (bad magic bytes)");
  }
  Reader r(path, bytes);
  ParameterFileInfo& info = parsed.info;
  const std::size_t scalar_size = parse_header(path, r, info);
  const std::uint64_t count = r.uint(4, "the parameter count");
  if (count > kMaxCount) {
    throw ParameterFileError(path, fmt::format("corrupt: {} parameters", count));
  }
  std::set<std::string> seen;
  for (std::uint64_t k = 0; k < count; ++k) {
    ParameterFileInfo::Entry entry;
    parsed.offsets.push_back(parse_entry(path, r, scalar_size, entry));
    if (!seen.insert(entry.name).second) {
      throw ParameterFileError(path, fmt::format("duplicate parameter '{}'", entry.name));
    }
    info.entries.push_back(std::move(entry));
  }
  const std::size_t body = r.pos();
  const std::uint64_t checksum = r.uint(8, "the checksum");
  if (r.remaining() != 0) {
    throw ParameterFileError(
        path,
        fmt::format("{} unexpected bytes after the checksum at offset {}", r.remaining(), r.pos()));
  }
  if (checksum != fnv1a(bytes.data(), body)) {
    throw ParameterFileError(path, "corrupt: the checksum does not match the contents");
  }
  return parsed;
}

template <typename T>
Matrix<T> decode_entry(const ParsedParameterFile& file, std::size_t k) {
  using Bits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
  const ParameterFileInfo::Entry& entry = file.info.entries.at(k);
  const std::size_t offset = file.offsets.at(k);
  Matrix<T> m(entry.rows, entry.cols);
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(m.data(), file.bytes.data() + offset, sizeof(T) * std::size_t(m.size()));
  } else {
    for (Index i = 0; i < m.size(); ++i) {
      Bits bits = 0;
      for (std::size_t b = 0; b < sizeof(T); ++b) {
        bits |= Bits(static_cast<unsigned char>(file.bytes[offset + i * sizeof(T) + b])) << (8 * b);
      }
      m.data()[i] = std::bit_cast<T>(bits);
    }
  }
  return m;
}

#define HNN_INSTANTIATE(T)                                                           \
  template std::string encode_parameter_file(std::string_view,                       \
                                             const std::vector<NamedParameter<T>>&); \
  template Matrix<T> decode_entry(const ParsedParameterFile&, std::size_t);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::nn
