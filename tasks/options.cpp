#include "tasks/options.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "tasks/error.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// "200-200" (metrics.json's form) or [200, 200] -> {200, 200}; throws Error on anything else.
std::vector<int> widths_from_json(const json& j) {
  const std::string text = j.is_array() ? j.dump() : j.get<std::string>();
  const auto bad = [&] {
    return Error(fmt::format("hidden '{}' is not widths of 1..{} joined by '-' (like 200-200)",
                             text, kMaxWidth));
  };
  std::vector<int> widths;
  if (j.is_array()) {
    for (const json& w : j) widths.push_back(json_integer<int>(w, "a hidden width"));
  } else {
    std::stringstream in(text);
    for (std::string w; std::getline(in, w, '-');) {
      int width = 0;
      const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), width);
      if (ec != std::errc() || end != w.data() + w.size()) throw bad();
      widths.push_back(width);
    }
  }
  if (widths.empty()) throw bad();
  for (int w : widths)
    if (w < 1 || w > kMaxWidth) throw bad();
  return widths;
}

}  // namespace

std::string_view to_string(Dtype dtype) { return dtype == Dtype::kFloat ? "float" : "double"; }
std::string_view to_string(Preset preset) { return preset == Preset::kLean ? "lean" : "paper"; }
std::vector<std::string> dtype_names() { return {"float", "double"}; }
std::vector<std::string> preset_names() { return {"paper", "lean"}; }
std::vector<std::string> model_names() { return {"hnn", "baseline", "dhnn", "lnn"}; }

Dtype parse_dtype(std::string_view name) {
  if (name == "float") return Dtype::kFloat;
  if (name == "double") return Dtype::kDouble;
  throw Error(fmt::format("dtype must be float or double, got '{}'", name));
}

Preset parse_preset(std::string_view name) {
  if (name == "paper") return Preset::kPaper;
  if (name == "lean") return Preset::kLean;
  throw Error(fmt::format("preset must be paper or lean, got '{}'", name));
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

json RunSettings::to_json() const {
  return {{"task", task},
          {"model", nn::to_string(model)},
          {"seed", seed},
          {"dtype", tasks::to_string(dtype)},
          {"preset", tasks::to_string(preset)},
          {"threads", threads},
          {"steps", train.steps},
          {"batch_size", train.batch_size},
          {"hidden", join_widths(train.hidden)},
          {"learning_rate", train.learning_rate},
          {"weight_decay", train.weight_decay},
          {"lr_schedule", to_string(train.lr_schedule)},
          {"data_file", data_file},
          {"task_settings", task_settings}};
}

RunOptions options_from_json(const json& j, const std::string& where) {
  RunOptions o;
  try {
    o.task = j.at("task");
    o.model = parse_model(j.at("model").get<std::string>());
    o.seed = json_integer<std::uint64_t>(j.at("seed"), "seed");
    o.dtype = parse_dtype(j.at("dtype").get<std::string>());
    o.preset = parse_preset(j.value("preset", "paper"));  // runs before the presets have none
    o.threads = json_integer<int>(j.value("threads", json(2)), "threads");
    o.steps = json_integer<int>(j.at("steps"), "steps");
    o.batch_size = json_integer<int>(j.at("batch_size"), "batch_size");
    o.hidden = widths_from_json(j.at("hidden"));
    o.learning_rate = j.at("learning_rate").get<double>();
    if (j.contains("weight_decay")) o.weight_decay = j["weight_decay"].get<double>();
    // Runs from before the schedules trained at a constant rate.
    o.lr_schedule = parse_lr_schedule(j.value("lr_schedule", "constant"));
    o.data_file = j.value("data_file", "");
    o.task_settings = j.value("task_settings", json::object());
  } catch (const std::exception& e) {
    throw Error(fmt::format("{} does not hold a run's settings: {}", where, e.what()));
  }
  return o;
}

}  // namespace hnn::tasks
