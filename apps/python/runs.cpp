#include "apps/python/runs.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "apps/hnn/sweep/keys.h"
#include "apps/python/arrays.h"
#include "apps/python/interrupt.h"
#include "autodiff/parallel.h"
#include "tasks/options/train_options.h"
#include "tasks/run.h"

namespace hnn::python {

namespace {

using nlohmann::json;
using tasks::TrainOption;
using tasks::ValueKind;

// Options `hnn train` has that a call from Python does not take, and why.
std::string refused(const TrainOption& option) {
  if (option.lands == tasks::Lands::kPrintJson) return "the run object's .metrics holds them";
  if (option.lands == tasks::Lands::kResume) return "hnn.train takes it as its argument resume";
  return "";
}

// The table's names: what hnn.train takes (with '_' for '-': lr_schedule).
std::string option_names() {
  std::vector<std::string> names;
  for (const TrainOption& option : tasks::train_options())
    if (option.kind != ValueKind::kTask && refused(option).empty()) names.emplace_back(option.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

// The value in the form tasks::apply takes: checked by its kind as `hnn sweep` checks its
// keys (apps/hnn/sweep/keys.h), flags and folders as themselves.
json canonical(const TrainOption& option, const json& value) {
  switch (option.kind) {
    case ValueKind::kFlag:
      if (value.is_boolean()) return value;
      throw InputError(
          fmt::format("{}: expected True or False, got {}", option.name, value.dump()));
    case ValueKind::kFolder:
      if (value.is_string() && !value.get<std::string>().empty()) return value;
      throw InputError(
          fmt::format("{}: expected a folder's name, got {}", option.name, value.dump()));
    default:
      try {
        return app::sweep::checked_value(option, value);
      } catch (const std::invalid_argument& e) {
        throw InputError(fmt::format("{}: {}", option.name, e.what()));
      }
  }
}

using Asked = std::vector<std::pair<const TrainOption*, json>>;

// The options `hnn train --resume DIR` starts from (apps/hnn/commands/train.cpp): the run's own,
// from its checkpoint, continued to the steps asked if any (the table's continues_resume);
// refuses an option asked that could change the result (not the table's with_resume).
tasks::RunOptions resumed(const std::string& run_dir, const Asked& asked) {
  std::optional<int> steps;  // more steps: a finished run continued
  for (const auto& [option, value] : asked) {
    if (option->continues_resume) {
      steps = canonical(*option, value).get<int>();
    } else if (!option->with_resume) {
      std::string name(option->name);
      std::replace(name.begin(), name.end(), '-', '_');
      throw InputError(fmt::format(
          "{} cannot be combined with resume: a resumed run keeps its own settings", name));
    }
  }
  return tasks::resume_options(run_dir, steps);
}

// The options of `hnn train TASK --name value...`, or with `resume` a folder, of `hnn train
// --resume RESUME --name value...`: resumed()'s, with the options asked on top.
tasks::RunOptions run_options(const std::string& task, const json& given,
                              const std::string& resume) {
  Asked asked;
  if (resume.empty()) asked.emplace_back(tasks::find_train_option("task"), task);
  if (!resume.empty() && !task.empty())
    throw InputError("task cannot be combined with resume: a resumed run keeps its own settings");
  for (const auto& [key, value] : given.items()) {
    std::string name = key;
    std::replace(name.begin(), name.end(), '_', '-');
    const TrainOption* option = tasks::find_train_option(name);
    if (option == nullptr || option->kind == ValueKind::kTask)
      throw InputError(
          fmt::format("unknown option '{}' of hnn train (options: {})", key, option_names()));
    if (const std::string why = refused(*option); !why.empty())
      throw InputError(fmt::format("{}: not taken from Python: {}", key, why));
    if (!value.is_null()) asked.emplace_back(option, value);
  }
  // The table's order (its rows are one array): the task first, as the hnn program applies them.
  std::sort(asked.begin(), asked.end(), [](const auto& a, const auto& b) {
    return std::less<const TrainOption*>()(a.first, b.first);
  });
  tasks::RunOptions o = resume.empty() ? tasks::RunOptions{} : resumed(resume, asked);
  for (const auto& [option, value] : asked) {
    if (const std::string why = tasks::not_applicable(*option, o.task); !why.empty())
      throw InputError(fmt::format("{} {}", option->name, why));
    tasks::apply(*option, canonical(*option, value), o);
  }
  if (o.out.empty()) o.out = tasks::default_run_folder(o);
  return o;
}

// Restores the engine's thread count, which a run sets to its own (--threads), when it ends.
class KeepThreads {
 public:
  KeepThreads() : threads_(ad::num_threads()) {}
  ~KeepThreads() { ad::set_num_threads(threads_); }
  KeepThreads(const KeepThreads&) = delete;
  KeepThreads& operator=(const KeepThreads&) = delete;

 private:
  int threads_;
};

// Trains and writes the run folder; returns its path. Ctrl-C stops after the step, with a
// checkpoint, and raises KeyboardInterrupt (resume with resume=OUT, or hnn train --resume OUT).
std::string train(const std::string& task, const std::string& options_json,
                  const std::string& resume) {
  tasks::RunOptions o = run_options(task, json::parse(options_json), resume);
  Interrupt interrupt;
  o.stop = interrupt.signal();
  const KeepThreads keep;
  try {
    py::gil_scoped_release free;
    tasks::run_training(o);
  } catch (const tasks::TrainingInterrupted&) {
    Interrupt::raise_keyboard_interrupt();
  }
  return o.out.string();
}

}  // namespace

void bind_runs(py::module_& m) {
  m.def("_train", &train, py::arg("task"), py::arg("options_json"), py::arg("resume") = "");
}

}  // namespace hnn::python
