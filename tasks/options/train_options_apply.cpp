// apply(): where each option of `hnn train`'s table (train_options.cpp) lands in RunOptions;
// the lookups in the table and the names of its choices.

#include <fmt/format.h>

#include "nn/enum_names.h"
#include "tasks/options/train_options.h"
#include "tasks/train/loop.h"

namespace hnn::tasks {

using nlohmann::json;

void apply(const TrainOption& option, const json& v, RunOptions& o) {
  switch (option.lands) {
    case Lands::kTask:
      o.task = v.get<std::string>();
      return;
    case Lands::kModel:
      o.model = parse_model(v.get<std::string>());
      return;
    case Lands::kSeed:
      o.seed = v.get<std::uint64_t>();
      return;
    case Lands::kDtype:
      o.dtype = parse_dtype(v.get<std::string>());
      return;
    case Lands::kPreset:
      o.preset = parse_preset(v.get<std::string>());
      return;
    case Lands::kThreads:
      o.threads = v.get<int>();
      return;
    case Lands::kSteps:
      o.steps = v.get<int>();
      return;
    case Lands::kBatchSize:
      o.batch_size = v.get<int>();
      return;
    case Lands::kHidden:
      o.hidden = v.get<std::vector<int>>();
      return;
    case Lands::kLearningRate:
      o.learning_rate = v.get<double>();
      return;
    case Lands::kLrSchedule:
      o.lr_schedule = parse_lr_schedule(v.get<std::string>());
      return;
    case Lands::kOptimizer:
      o.optimizer = parse_optimizer(v.get<std::string>());
      return;
    case Lands::kDataFile:
      o.data_file = v.get<std::string>();
      return;
    case Lands::kOut:
      o.out = v.get<std::string>();
      return;
    case Lands::kQuiet:
      o.quiet = v.get<bool>();
      return;
    case Lands::kPrintJson:
      o.print_json = v.get<bool>();
      return;
    case Lands::kTaskSettings: {
      // The keys already set by their own options stay (the data task's, the rollout loss's).
      json settings = v;
      if (settings.is_object()) settings.update(o.task_settings);
      o.task_settings = std::move(settings);
      return;
    }
    case Lands::kCheckpointEvery:
      o.checkpoint_every = v.get<long>();
      return;
    case Lands::kResume:
      o.out = v.get<std::string>();
      o.resume = true;
      return;
    case Lands::kForce:
      o.force = v.get<bool>();
      return;
    case Lands::kTaskSetting:
      o.task_settings[std::string(option.key)] = v;
      return;
  }
}

const TrainOption* find_train_option(std::string_view name) {
  for (const TrainOption& option : train_options())
    if (option.name == name) return &option;
  return nullptr;
}

std::vector<std::string> loss_names() { return {"derivative", "rollout"}; }
std::vector<std::string> lr_schedule_names() { return nn::names_of(kLrScheduleNames); }

std::string not_applicable(const TrainOption& option, const std::string& task) {
  if (option.applies_to != AppliesTo::kDataTask || task == "data") return "";
  return fmt::format("applies to the data task only, not to '{}'", task);
}

}  // namespace hnn::tasks
