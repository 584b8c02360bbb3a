#include "tasks/options.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "tasks/report/json_values.h"
#include "tasks/task.h"

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

void check_train_config(const TrainConfig& c) {
  HNN_TASKS_CHECK(c.steps > 0, "--steps must be positive, got {}", c.steps);
  HNN_TASKS_CHECK(c.batch_size >= 0, "--batch must be >= 0, got {}", c.batch_size);
  HNN_TASKS_CHECK(c.learning_rate > 0 && std::isfinite(c.learning_rate),
                  "--lr must be a positive finite number, got {}", c.learning_rate);
  HNN_TASKS_CHECK(c.weight_decay >= 0 && std::isfinite(c.weight_decay),
                  "weight decay must be a finite number >= 0, got {}", c.weight_decay);
  HNN_TASKS_CHECK(!c.hidden.empty(), "--hidden needs at least one width");
  for (int w : c.hidden) {
    HNN_TASKS_CHECK(w > 0 && w <= kMaxWidth, "--hidden widths must be 1..{}, got {}", kMaxWidth, w);
  }
}

TrainConfig train_config(const Task& task, const RunOptions& o) {
  TrainConfig c = task.train_config();
  if (o.preset == Preset::kLean) c.hidden = task.lean_hidden();
  if (o.steps) c.steps = *o.steps;
  if (o.batch_size) c.batch_size = *o.batch_size;
  if (o.hidden) c.hidden = *o.hidden;
  if (o.learning_rate) c.learning_rate = *o.learning_rate;
  if (o.weight_decay) c.weight_decay = *o.weight_decay;
  if (o.lr_schedule) c.lr_schedule = *o.lr_schedule;
  return c;
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

namespace {

// Why a model that needs velocities does not fit a task, and which tasks it fits.
std::string needs_velocities_note(nn::ModelKind model) {
  if (!nn::needs_velocities(model)) return "";
  std::vector<std::string> fits;
  for (const std::string& name : task_names()) {
    const std::vector<nn::ModelKind> models = make_task(name)->models();
    if (std::find(models.begin(), models.end(), model) != models.end()) fits.push_back(name);
  }
  return fmt::format(
      ": an {} learns L(q, dq/dt) from coordinates and their velocities, which "
      "this task's states are not (tasks that have them: {})",
      nn::to_string(model), fmt::join(fits, ", "));
}

}  // namespace

RunSettings resolve(const Task& task, const RunOptions& o) {
  HNN_TASKS_CHECK(o.threads >= 1 && o.threads <= 256, "--threads must be 1..256, got {}",
                  o.threads);
  HNN_TASKS_CHECK(o.data_file.empty() || task.reads_data_file(),
                  "task '{}' does not read a data file (--data applies to measured-data tasks "
                  "such as real-pendulum)",
                  task.name());
  HNN_TASKS_CHECK(o.task_settings.is_object(), "task settings must be a JSON object, got {}",
                  o.task_settings.dump());
  task.check_task_settings(o.task_settings);
  const std::vector<nn::ModelKind> models = task.models();
  if (std::find(models.begin(), models.end(), o.model) == models.end()) {
    std::vector<std::string_view> names;
    for (nn::ModelKind m : models) names.push_back(nn::to_string(m));
    throw Error(fmt::format("task '{}' does not train a {} model (its models: {}){}", task.name(),
                            nn::to_string(o.model), fmt::join(names, ", "),
                            needs_velocities_note(o.model)));
  }
  RunSettings s{.task = task.name(),
                .model = o.model,
                .seed = o.seed,
                .dtype = o.dtype,
                .preset = o.preset,
                .threads = o.threads,
                .train = train_config(task, o),
                .data_file = o.data_file,
                .task_settings = o.task_settings};
  check_train_config(s.train);
  return s;
}

RunSettings validate(const RunOptions& o) {
  const RunSettings s = resolve(*make_task(o.task), o);
  HNN_TASKS_CHECK(!o.checkpoint_every || *o.checkpoint_every > 0,
                  "--checkpoint-every must be positive, got {}", o.checkpoint_every.value_or(0));
  HNN_TASKS_CHECK(!o.out.empty(), "an output folder is required");
  HNN_TASKS_CHECK(!std::filesystem::exists(o.out) || std::filesystem::is_directory(o.out),
                  "--out '{}' is a file, not a folder", o.out.string());
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
