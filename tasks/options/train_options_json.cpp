// The JSON form of a run's settings (metrics.json's settings, a checkpoint's): made from the
// table of `hnn train`'s options (train_options.cpp), so that a key is written and read back as
// the option that sets it; each value read back reaches RunOptions through apply().

#include <fmt/format.h>

#include <charconv>
#include <sstream>
#include <stdexcept>

#include "tasks/error.h"
#include "tasks/options.h"
#include "tasks/options/train_options.h"
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

// An option's setting in `s`, as RunSettings::to_json records it under the option's key.
json recorded_value(const TrainOption& option, const RunSettings& s) {
  switch (option.lands) {
    case Lands::kTask:
      return s.task;
    case Lands::kModel:
      return nn::to_string(s.model);
    case Lands::kSeed:
      return s.seed;
    case Lands::kDtype:
      return tasks::to_string(s.dtype);
    case Lands::kPreset:
      return tasks::to_string(s.preset);
    case Lands::kThreads:
      return s.threads;
    case Lands::kSteps:
      return s.train.steps;
    case Lands::kBatchSize:
      return s.train.batch_size;
    case Lands::kHidden:
      return join_widths(s.train.hidden);
    case Lands::kLearningRate:
      return s.train.learning_rate;
    case Lands::kLrSchedule:
      return to_string(s.train.lr_schedule);
    case Lands::kOptimizer:
      return to_string(s.train.optimizer);
    case Lands::kDataFile:
      return s.data_file;
    case Lands::kTaskSettings:
      return s.task_settings;
    default:
      throw std::logic_error(fmt::format("--{} is not recorded in a run's settings", option.name));
  }
}

// A recorded value as apply() takes it; throws naming the key.
json from_record(const TrainOption& option, const json& j) {
  const std::string key(option.key);
  switch (option.kind) {
    case ValueKind::kSeed:
      return json_integer<std::uint64_t>(j, key);
    case ValueKind::kInt:
      return json_integer<int>(j, key);
    case ValueKind::kHidden:
      return widths_from_json(j);
    case ValueKind::kPositiveReal:
      return j.get<double>();
    case ValueKind::kJsonObject:
      return j;
    default:
      return j.get<std::string>();
  }
}

// The options RunSettings::to_json records: those with a key outside the task's settings.
bool recorded(const TrainOption& option) {
  return !option.key.empty() && option.lands != Lands::kTaskSetting;
}

}  // namespace

json RunSettings::to_json() const {
  json j;
  for (const TrainOption& option : train_options())
    if (recorded(option)) j[std::string(option.key)] = recorded_value(option, *this);
  j["weight_decay"] = train.weight_decay;  // no option sets it: each task's TrainConfig does
  // Facts of a run rather than options; absent where they do not apply (runs of the tasks
  // without a data file, runs trained in one go), so those runs' files keep their keys.
  if (!data_sha256.empty()) j["data_sha256"] = data_sha256;
  if (!continued_from.empty()) j["continued_from"] = continued_from;
  return j;
}

RunOptions options_from_json(const json& j, const std::string& where) {
  RunOptions o;
  try {
    for (const TrainOption& option : train_options()) {
      if (!recorded(option)) continue;
      const std::string key(option.key);
      const json value = j.contains(key) || option.recorded_default.empty()
                             ? j.at(key)
                             : json::parse(option.recorded_default);
      apply(option, from_record(option, value), o);
    }
    if (j.contains("weight_decay")) o.weight_decay = j["weight_decay"].get<double>();
    if (j.contains("data_sha256")) o.data_sha256 = j["data_sha256"].get<std::string>();
    if (j.contains("continued_from"))
      o.continued_from = j["continued_from"].get<std::vector<int>>();
  } catch (const std::exception& e) {
    throw Error(fmt::format("{} does not hold a run's settings: {}", where, e.what()));
  }
  return o;
}

}  // namespace hnn::tasks
