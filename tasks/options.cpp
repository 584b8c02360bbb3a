#include "tasks/options.h"

#include <fmt/format.h>

#include <optional>
#include <stdexcept>

#include "nn/enum_names.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

constexpr nn::NameTable<Dtype, 2> kDtypeNames{
    {{Dtype::kFloat, "float"}, {Dtype::kDouble, "double"}}};
constexpr nn::NameTable<Preset, 2> kPresetNames{
    {{Preset::kPaper, "paper"}, {Preset::kLean, "lean"}}};
constexpr nn::NameTable<OptimizerKind, 2> kOptimizerNames{
    {{OptimizerKind::kAdam, "adam"}, {OptimizerKind::kAdamW, "adamw"}}};

}  // namespace

std::string_view to_string(Dtype dtype) { return nn::name_of(kDtypeNames, dtype); }
std::string_view to_string(Preset preset) { return nn::name_of(kPresetNames, preset); }
std::vector<std::string> dtype_names() { return nn::names_of(kDtypeNames); }
std::string_view to_string(OptimizerKind optimizer) {
  return nn::name_of(kOptimizerNames, optimizer);
}
std::vector<std::string> preset_names() { return nn::names_of(kPresetNames); }
std::vector<std::string> optimizer_names() { return nn::names_of(kOptimizerNames); }
std::vector<std::string> model_names() { return nn::names_of(nn::kModelKindNames); }

Dtype parse_dtype(std::string_view name) {
  if (const std::optional<Dtype> dtype = nn::find_name(kDtypeNames, name)) return *dtype;
  throw Error(fmt::format("dtype must be {}, got '{}'", nn::join_names(kDtypeNames, " or "), name));
}

Preset parse_preset(std::string_view name) {
  if (const std::optional<Preset> preset = nn::find_name(kPresetNames, name)) return *preset;
  throw Error(
      fmt::format("preset must be {}, got '{}'", nn::join_names(kPresetNames, " or "), name));
}

OptimizerKind parse_optimizer(std::string_view name) {
  if (const std::optional<OptimizerKind> kind = nn::find_name(kOptimizerNames, name)) return *kind;
  throw Error(
      fmt::format("optimizer must be {}, got '{}'", nn::join_names(kOptimizerNames, " or "), name));
}

nn::ModelKind parse_model(std::string_view name) {
  try {
    return nn::parse_model_kind(name);
  } catch (const std::invalid_argument& e) {
    throw Error(e.what());
  }
}

std::string join_widths(const std::vector<int>& widths) {
  std::string s;
  for (int w : widths) s += (s.empty() ? "" : "-") + std::to_string(w);
  return s;
}

}  // namespace hnn::tasks
