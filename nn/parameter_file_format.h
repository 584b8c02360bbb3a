#pragma once
// The bytes of a parameter file (layout in nn/parameter_file.h): encoding a list of named
// matrices, and reading a file back with every check of its layout, bounds and checksum. Matching
// a file against a module is nn/parameter_file.cpp's.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "nn/parameter_file.h"

namespace hnn::nn {

/// A parameter file read and checked whole: what it holds, where each entry's values start in
/// `bytes` (offsets[k] for info.entries[k]), and the bytes themselves.
struct ParsedParameterFile {
  ParameterFileInfo info;
  std::vector<std::size_t> offsets;
  std::string bytes;
};

/// The bytes of a file holding `kind` and `parameters` (in their order), checksum included.
template <typename T>
std::string encode_parameter_file(std::string_view kind,
                                  const std::vector<NamedParameter<T>>& parameters);

/// Reads `path` and checks its magic, version, scalar type, bounds, unique names and checksum;
/// throws ParameterFileError naming the file and the first problem. Corrupt counts and shapes
/// are refused before anything is allocated for them.
ParsedParameterFile parse_parameter_file(const std::filesystem::path& path);

/// The values of entry `k` of `file`, whose scalar type must be T's (not checked here).
template <typename T>
Matrix<T> decode_entry(const ParsedParameterFile& file, std::size_t k);

}  // namespace hnn::nn
