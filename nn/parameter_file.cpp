#include "nn/parameter_file.h"

#include <fmt/format.h>

#include <map>
#include <set>

#include "nn/atomic_file.h"
#include "nn/enum_names.h"
#include "nn/parameter_file_format.h"

namespace hnn::nn {

namespace fs = std::filesystem;

ParameterFileError::ParameterFileError(const fs::path& path, const std::string& reason)
    : std::runtime_error(fmt::format("parameter file '{}': {}", path.string(), reason)),
      path_(path),
      reason_(reason) {}

namespace {
constexpr NameTable<ScalarType, 2> kScalarTypeNames{{
    {ScalarType::kFloat32, "float32"},
    {ScalarType::kFloat64, "float64"},
}};
}  // namespace

std::string_view to_string(ScalarType type) { return name_of(kScalarTypeNames, type); }

template <typename T>
void save_parameters(const fs::path& path, std::string_view kind,
                     const std::vector<NamedParameter<T>>& parameters) {
  std::set<std::string> names;
  for (const NamedParameter<T>& p : parameters) {
    if (!names.insert(p.name).second) {
      throw ParameterFileError(path, fmt::format("duplicate parameter name '{}'", p.name));
    }
  }
  try {
    write_file_atomic(path, encode_parameter_file(kind, parameters));
  } catch (const FileWriteError& e) {
    throw ParameterFileError(path,
                             fmt::format("cannot write it ({}): {}", e.step(), e.code().message()));
  }
}

template <typename T>
void load_parameters(const fs::path& path, std::string_view kind,
                     const std::vector<NamedParameter<T>>& parameters) {
  const ParsedParameterFile parsed = parse_parameter_file(path);
  const ParameterFileInfo& info = parsed.info;
  if (info.scalar != scalar_type_of<T>()) {
    throw ParameterFileError(
        path, fmt::format("holds {} parameters but the model is {} (load into a model of the "
                          "file's type, then cast)",
                          to_string(info.scalar), to_string(scalar_type_of<T>())));
  }
  if (info.kind != kind) {
    throw ParameterFileError(
        path, fmt::format("holds a '{}' model but the model is '{}'", info.kind, kind));
  }
  std::map<std::string, std::size_t> by_name;
  for (std::size_t k = 0; k < info.entries.size(); ++k) by_name[info.entries[k].name] = k;
  std::vector<Matrix<T>> values;
  values.reserve(parameters.size());
  for (const NamedParameter<T>& p : parameters) {
    const auto it = by_name.find(p.name);
    if (it == by_name.end()) {
      throw ParameterFileError(path, fmt::format("has no parameter '{}' ({} expected, {} in the "
                                                 "file)",
                                                 p.name, parameters.size(), info.entries.size()));
    }
    const ParameterFileInfo::Entry& e = info.entries[it->second];
    if (e.rows != p.var.rows() || e.cols != p.var.cols()) {
      throw ParameterFileError(path,
                               fmt::format("parameter '{}' is {} in the file but {} in the "
                                           "model",
                                           p.name, ad::shape_str(e.rows, e.cols), p.var.shape()));
    }
    values.push_back(decode_entry<T>(parsed, it->second));
    by_name.erase(it);
  }
  if (!by_name.empty()) {
    throw ParameterFileError(path, fmt::format("has parameter '{}' that the model lacks ({} extra)",
                                               by_name.begin()->first, by_name.size()));
  }
  // Everything matched: only now is the model changed.
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    ad::Var<T> leaf = parameters[i].var;
    leaf.mutable_value() = std::move(values[i]);
  }
}

template <typename T>
void save_parameters(const fs::path& path, const Module<T>& module) {
  save_parameters<T>(path, module.kind(), module.named_parameters());
}

template <typename T>
void load_parameters(const fs::path& path, Module<T>& module) {
  load_parameters<T>(path, module.kind(), module.named_parameters());
}

ParameterFileInfo read_parameter_file_info(const fs::path& path) {
  return parse_parameter_file(path).info;
}

#define HNN_INSTANTIATE(T)                                              \
  template void save_parameters(const fs::path&, std::string_view,      \
                                const std::vector<NamedParameter<T>>&); \
  template void load_parameters(const fs::path&, std::string_view,      \
                                const std::vector<NamedParameter<T>>&); \
  template void save_parameters(const fs::path&, const Module<T>&);     \
  template void load_parameters(const fs::path&, Module<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::nn
