#pragma once
// `hnn train`'s options, declared once. Each row of the table says what the option takes (its
// kind and checks), how --help shows it, whether it may be given with --resume, whether it is a
// key of `hnn sweep`'s spec (or why the sweep sets it itself), which tasks it applies to, and
// where its value lands: a RunOptions field or a key of the task's settings. From it are made
// the command line and the resume guard (apps/hnn/commands/train.cpp), the sweep keys
// (apps/hnn/sweep/keys.cpp) and the JSON form of metrics.json and checkpoints
// (train_options_json.cpp).
// Every front end turns what it reads into one canonical JSON value per option and hands it to
// apply(), the one place an option reaches RunOptions.

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tasks/options.h"

namespace hnn::tasks {

/// What an option's value is; the checks each front end makes of it.
enum class ValueKind {
  kTask,            ///< a task's name (the registry's, tasks/experiments/registry.h)
  kChoice,          ///< one of TrainOption::choices()
  kSeed,            ///< an integer from 0 to 2^64 - 1
  kInt,             ///< an integer from TrainOption::min to max
  kHidden,          ///< hidden widths, each 1..kMaxWidth
  kPositiveReal,    ///< a finite number > 0
  kFraction,        ///< a number in (0, 1)
  kAutoOrFraction,  ///< "auto" or a number in (0, 1)
  kAutoOrPositive,  ///< "auto" or a finite number > 0
  kFile,            ///< a file's name
  kFolder,          ///< a folder's name (made when missing)
  kRunFolder,       ///< an existing run folder
  kJsonObject,      ///< a JSON object (on the command line, its text)
  kColumns,         ///< a data file's columns (on the command line, comma-separated)
  kText,            ///< a non-empty string
  kFlag,            ///< given or not
};

/// The tasks an option applies to. kFieldTasks is checked by each task (Task::check_task_settings
/// refuses a setting it does not know); kDataTask before the task is opened.
enum class AppliesTo { kEveryTask, kDataTask, kFieldTasks };

/// Where an option's value lands: a field of RunOptions, or (kTaskSetting) TrainOption::key of
/// RunOptions::task_settings.
enum class Lands {
  kTask,
  kModel,
  kSeed,
  kDtype,
  kPreset,
  kThreads,
  kSteps,
  kBatchSize,
  kHidden,
  kLearningRate,
  kLrSchedule,
  kOptimizer,
  kDataFile,
  kOut,
  kQuiet,
  kPrintJson,
  kTaskSettings,
  kCheckpointEvery,
  kResume,  ///< out, with resume set: the rest comes from the checkpoint (run.h resume_options)
  kForce,
  kTaskSetting
};

struct TrainOption {
  std::string_view name;  ///< "model" is --model; the kTask option is the positional TASK
  ValueKind kind;
  std::string_view help;        ///< --help's text; "{}": the tasks (kTask) or choices (kChoice)
  std::string_view group = "";  ///< --help's heading; "" the general options
  std::string_view default_shown = "";  ///< --help's default: RunOptions{}'s value, as text
  bool with_resume = false;             ///< may be given with --resume: cannot change a result
  /// May be given with --resume to continue the run further (--steps: resume_options, run.h).
  bool continues_resume = false;
  std::string_view sweep_owned = "";  ///< why `hnn sweep` sets it itself; "" a sweep key
  int sweep_rank = -1;                ///< a sweep key's place in run folder names and table columns
  AppliesTo applies_to = AppliesTo::kEveryTask;
  Lands lands = Lands::kTaskSetting;
  /// The task settings' key (kTaskSetting), or RunSettings::to_json's key; "": not recorded.
  std::string_view key = "";
  /// RunSettings::to_json's key in runs from before it existed, as JSON; "": always there.
  std::string_view recorded_default = "";
  long long min = 0, max = 0;                       ///< kInt's range
  bool range_in_help = false;                       ///< kInt: checked by CLI::Range
  std::vector<std::string> (*choices)() = nullptr;  ///< kChoice's names
  std::string_view noun = "";                       ///< kChoice: "unknown {noun} 'x'"
  /// --help's default is each task's own: RunSettings::to_json's `key` for the task alone.
  bool default_by_task = false;
};

/// Every option, in the order of `hnn train --help`.
std::span<const TrainOption> train_options();

namespace detail {
/// The rows of the field tasks' training methods (train_options_methods.cpp), which
/// train_options() lists after its own.
std::span<const TrainOption> training_method_options();
}  // namespace detail
/// The option named so ("model", "task"), or nullptr.
const TrainOption* find_train_option(std::string_view name);

/// The training losses: dx/dt targets, or the model's field integrated over windows of states.
std::vector<std::string> loss_names();
std::vector<std::string> lr_schedule_names();

/// Why `option` does not apply to `task` ("applies to the data task only, not to 'spring'"), or
/// "" when it does or when the task decides (AppliesTo::kFieldTasks).
std::string not_applicable(const TrainOption& option, const std::string& task);

/// Sets `option`'s value in `o`. `value` is canonical: a string for names, files and folders; a
/// number; a list of widths or of column names; an object of task settings; true for a flag.
/// Options written as task settings win over the same keys in --settings, whatever the order.
/// Throws Error (or nlohmann::json's exceptions) on a value that is not of the option's kind.
void apply(const TrainOption& option, const nlohmann::json& value, RunOptions& o);

}  // namespace hnn::tasks
