#pragma once
// Parameter files: a module's (or any named list of) parameters in a small, versioned binary
// format, written atomically (nn/atomic_file.h). Models (RUN/params.bin) and the matrices of
// training checkpoints are kept in it.
//
// Layout (little-endian):
//   "HNNPARAM"                          8 bytes of magic
//   u32 format version                  kParameterFileVersion
//   u8  scalar type, u8[3] zero         1 = float32, 2 = float64
//   u32 length + bytes                  the module's kind() ("hnn:tanh")
//   u32 count                           number of parameters
//   count x { u32 length + name bytes, u64 rows, u64 cols, rows*cols scalars row-major }
//   u64 FNV-1a checksum                 of every byte before it
// Loading reads and checks the whole file first (nn/parameter_file_format.h) and changes the
// module only when everything matches (kind, scalar type, names, shapes), so a failed load never
// leaves it half-loaded.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "nn/module.h"

namespace hnn::nn {

inline constexpr std::uint32_t kParameterFileVersion = 1;

/// A parameter file that cannot be written or read, or does not fit the module. what() is
/// "parameter file '<path>': <reason>".
class ParameterFileError : public std::runtime_error {
 public:
  ParameterFileError(const std::filesystem::path& path, const std::string& reason);
  const std::filesystem::path& path() const { return path_; }
  const std::string& reason() const { return reason_; }

 private:
  std::filesystem::path path_;
  std::string reason_;
};

enum class ScalarType : std::uint8_t { kFloat32 = 1, kFloat64 = 2 };
std::string_view to_string(ScalarType type);
template <typename T>
constexpr ScalarType scalar_type_of() {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>);
  return std::is_same_v<T, float> ? ScalarType::kFloat32 : ScalarType::kFloat64;
}

/// What a parameter file holds, without its values.
struct ParameterFileInfo {
  std::uint32_t version = 0;
  ScalarType scalar = ScalarType::kFloat64;
  std::string kind;
  struct Entry {
    std::string name;
    Index rows = 0, cols = 0;
  };
  std::vector<Entry> entries;
};

/// Writes module.kind() and module.named_parameters() to `path` atomically (write_file_atomic);
/// throws ParameterFileError if it cannot.
template <typename T>
void save_parameters(const std::filesystem::path& path, const Module<T>& module);

/// Loads `path` into `module`; throws ParameterFileError (naming the file and the reason) for a
/// foreign, truncated or corrupt file, another format version, another scalar type, another
/// kind, or different parameter names or shapes, and then leaves the module unchanged.
template <typename T>
void load_parameters(const std::filesystem::path& path, Module<T>& module);

/// The same for an explicit kind and parameter list (e.g. several modules saved together; the
/// names must be unique). Loading assigns into the given leaves.
template <typename T>
void save_parameters(const std::filesystem::path& path, std::string_view kind,
                     const std::vector<NamedParameter<T>>& parameters);
template <typename T>
void load_parameters(const std::filesystem::path& path, std::string_view kind,
                     const std::vector<NamedParameter<T>>& parameters);

/// Reads and checks a parameter file's header and layout (throws ParameterFileError like
/// loading).
ParameterFileInfo read_parameter_file_info(const std::filesystem::path& path);

}  // namespace hnn::nn
