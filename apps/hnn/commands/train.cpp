// `hnn train`: one model on a task, or an interrupted run resumed; Ctrl-C stops after the step
// with a checkpoint.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/help_format.h"
#include "apps/hnn/commands/summary.h"
#include "apps/hnn/commands/validators.h"
#include "tasks/experiments/registry.h"
#include "tasks/options/train_options.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

std::string task_list() {
  std::string s;
  for (const std::string& t : tasks::task_names()) s += (s.empty() ? "" : ", ") + t;
  return s;
}

// Ctrl-C (SIGINT) or SIGTERM during training: the loop stops after its step and checkpoints.
// A signal handler can reach only globals, so this is the program's one.
tasks::StopSignal g_stop;

extern "C" void on_stop_signal(int sig) {
  if (g_stop.armed && !g_stop.requested) {
    g_stop.requested = true;
    constexpr char kNote[] = "\nhnn: stopping after this step (press Ctrl-C again to quit now)\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, kNote, sizeof(kNote) - 1);
    return;
  }
  std::signal(sig, SIG_DFL);  // nothing would notice, or asked twice: the default action, now
  std::raise(sig);
}

void install_stop_handler() {
  struct sigaction action = {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM}) sigaction(sig, &action, nullptr);
}

// Trains; on a stop request, says how to resume and exits 130 (128 + SIGINT).
void train_until_done_or_stopped(tasks::RunOptions o) {
  install_stop_handler();
  o.stop = &g_stop;
  try {
    const nlohmann::json m = tasks::run_training(o);
    if (o.print_json) {
      fmt::print("{}\n", m.dump(2));
    } else {
      fmt::print("{}  files      {}: {}\n", metrics_summary(m), o.out.string(), files_in(o.out));
    }
    print_warnings(m);
  } catch (const tasks::TrainingInterrupted& e) {
    fmt::print(stderr, "hnn: {}\nhnn: resume with: hnn train --resume {}\n", e.what(),
               o.out.string());
    throw CLI::RuntimeError(130);
  }
}

// One option's value as CLI11 reads it: the member its kind binds, so numbers are parsed by
// CLI11 as they always were.
struct Given {
  std::string text;
  std::vector<std::string> texts;
  std::vector<long long> integers;
  long long integer = 0;
  std::uint64_t seed = 0;
  double real = 0;
  bool flag = false;
};

// --settings: a JSON object, or one line saying why not.
nlohmann::json task_settings(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) {
    throw std::invalid_argument(
        fmt::format("--settings must be a JSON object like '{{\"trials\": 20}}', got '{}'", text));
  }
  return j;
}

// "2000 (spring, pendulum), 10000 (two-body)": each task's own value of `option`, as a run of
// the task alone records it.
std::string defaults_by_task(const tasks::TrainOption& option) {
  std::vector<std::pair<std::string, std::string>> groups;  // a value and its tasks
  for (const std::string& name : tasks::task_names()) {
    const std::unique_ptr<tasks::Task> task = tasks::make_task(name);
    const tasks::RunOptions alone{.task = name, .model = task->models().front()};
    const nlohmann::json value = tasks::resolve(*task, alone).to_json().at(std::string(option.key));
    const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
    const auto group =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == text; });
    if (group == groups.end()) {
      groups.emplace_back(text, name);
    } else {
      group->second += ", " + name;
    }
  }
  std::string out;
  for (const auto& [value, names] : groups)
    out += fmt::format("{}{} ({})", out.empty() ? "" : ", ", value, names);
  return out;
}

// --help's text of `option`: its "{}" filled with the tasks or the choices, and its default.
std::string help_text(const tasks::TrainOption& option) {
  std::string help(option.help);
  if (option.kind == tasks::ValueKind::kTask) help = fmt::format(fmt::runtime(help), task_list());
  if (option.kind == tasks::ValueKind::kChoice && help.find("{}") != std::string::npos)
    help = fmt::format(fmt::runtime(help), fmt::join(option.choices(), ", "));
  if (option.default_by_task)
    help += fmt::format(" (default: each task's own: {})", defaults_by_task(option));
  return help;
}

// What --help shows after an option's name (HelpFormatter, help_format.h).
std::string metavar(const tasks::TrainOption& option) {
  using tasks::ValueKind;
  switch (option.kind) {
    case ValueKind::kChoice:
      return "NAME";
    case ValueKind::kSeed:
    case ValueKind::kInt:
      return "N";
    case ValueKind::kHidden:
      return "N ...";
    case ValueKind::kPositiveReal:
    case ValueKind::kFraction:
      return "X";
    case ValueKind::kAutoOrFraction:
    case ValueKind::kAutoOrPositive:
      return "auto|X";
    case ValueKind::kFile:
      return "FILE";
    case ValueKind::kFolder:
    case ValueKind::kRunFolder:
      return "DIR";
    case ValueKind::kJsonObject:
      return "JSON";
    case ValueKind::kColumns:
      return "COLUMNS";
    case ValueKind::kText:
      return text_metavar(option.name);
    default:  // the positional TASK, a flag
      return "";
  }
}

// `option` on the command line, bound to `given` and checked by its kind.
CLI::Option* add_option(CLI::App& cmd, const tasks::TrainOption& option, Given& given) {
  using tasks::ValueKind;
  const std::string help = help_text(option);
  if (option.kind == ValueKind::kTask)
    return cmd.add_option(std::string(option.name), given.text, help);
  const std::string name = "--" + std::string(option.name);
  switch (option.kind) {
    case ValueKind::kFlag:
      return cmd.add_flag(name, given.flag, help);
    case ValueKind::kChoice:
      return cmd.add_option(name, given.text, help)->check(CLI::IsMember(option.choices()));
    case ValueKind::kSeed:
      return cmd.add_option(name, given.seed, help)->check(seed_value());
    case ValueKind::kInt: {
      CLI::Option* o = cmd.add_option(name, given.integer, help);
      if (option.range_in_help) return o->check(CLI::Range(option.min, option.max));
      return o->check(integer_in(option.min, option.max));
    }
    case ValueKind::kHidden:
      return cmd.add_option(name, given.integers, help)->check(integer_in(1, tasks::kMaxWidth));
    case ValueKind::kPositiveReal:
      return cmd.add_option(name, given.real, help)->check(positive_real());
    case ValueKind::kFraction:
      return cmd.add_option(name, given.real, help)
          ->check(CLI::Range(0.0, 1.0).description("in (0, 1)"));
    case ValueKind::kAutoOrFraction:
      return cmd.add_option(name, given.text, help)->check(auto_or_fraction());
    case ValueKind::kAutoOrPositive:
      return cmd.add_option(name, given.text, help)->check(auto_or_positive());
    case ValueKind::kColumns:
      return cmd.add_option(name, given.texts, help)->delimiter(',');
    case ValueKind::kRunFolder:
      return cmd.add_option(name, given.text, help)->check(CLI::ExistingDirectory);
    default:  // a file, a folder, a JSON object's text, a column's name
      return cmd.add_option(name, given.text, help);
  }
}

// The value given, as tasks::apply takes it; null for an empty --settings (as if not given).
nlohmann::json given_value(const tasks::TrainOption& option, const Given& given) {
  using tasks::ValueKind;
  switch (option.kind) {
    case ValueKind::kFlag:
      return given.flag;
    case ValueKind::kSeed:
      return given.seed;
    case ValueKind::kInt:
      return given.integer;
    case ValueKind::kHidden:
      return given.integers;
    case ValueKind::kPositiveReal:
    case ValueKind::kFraction:
      return given.real;
    case ValueKind::kAutoOrFraction:  // checked by auto_or_fraction() or auto_or_positive()
    case ValueKind::kAutoOrPositive:
      return given.text == "auto" ? nlohmann::json("auto") : nlohmann::json(std::stod(given.text));
    case ValueKind::kColumns:
      return given.texts;
    case ValueKind::kJsonObject:
      return given.text.empty() ? nlohmann::json() : task_settings(given.text);
    default:
      return given.text;
  }
}

// "--model"; "task" for the positional TASK.
std::string cli_name(const tasks::TrainOption& option) {
  const std::string name(option.name);
  return option.kind == tasks::ValueKind::kTask ? name : "--" + name;
}

// The options of a run from those given. With --resume, the run's own from its checkpoint, and
// on top only the options that cannot change the result (the table's with_resume).
tasks::RunOptions run_options(const CLI::App& cmd, const std::vector<Given>& given) {
  const std::span<const tasks::TrainOption> table = tasks::train_options();
  std::vector<std::size_t> asked;  // the options given, in the table's order
  for (std::size_t i = 0; i < table.size(); ++i)
    if (cmd.get_option(cli_name(table[i]))->count() > 0) asked.push_back(i);
  const auto is = [&](tasks::Lands lands) {
    return [&table, lands](std::size_t i) { return table[i].lands == lands; };
  };
  tasks::RunOptions o;
  if (const auto resume = std::find_if(asked.begin(), asked.end(), is(tasks::Lands::kResume));
      resume != asked.end()) {
    std::optional<int> steps;  // more steps: a finished run continued
    for (std::size_t i : asked) {
      if (table[i].continues_resume) {
        steps = given_value(table[i], given[i]).get<int>();
      } else if (!table[i].with_resume) {
        throw std::invalid_argument(
            fmt::format("{} cannot be combined with --resume: a resumed run keeps its own settings",
                        cli_name(table[i])));
      }
    }
    o = tasks::resume_options(given[*resume].text, steps);
  } else if (const auto task = std::find_if(asked.begin(), asked.end(), is(tasks::Lands::kTask));
             task == asked.end() || given[*task].text.empty()) {
    throw std::invalid_argument("train needs a TASK (or --resume DIR)");
  }
  for (std::size_t i : asked) {
    const nlohmann::json value = given_value(table[i], given[i]);
    if (value.is_null()) continue;
    if (const std::string why = tasks::not_applicable(table[i], o.task); !why.empty())
      throw std::invalid_argument(fmt::format("{} {}", cli_name(table[i]), why));
    tasks::apply(table[i], value, o);  // the task first: it leads the table
  }
  return o;
}

}  // namespace

void add_train_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("train", "Train and evaluate one model on a task");
  const std::span<const tasks::TrainOption> table = tasks::train_options();
  auto given = std::make_shared<std::vector<Given>>(table.size());
  for (std::size_t i = 0; i < table.size(); ++i) {
    CLI::Option* option = add_option(*cmd, table[i], (*given)[i]);
    option->option_text(metavar(table[i]));
    if (!table[i].group.empty()) option->group(std::string(table[i].group));
    if (!table[i].default_shown.empty()) option->default_str(std::string(table[i].default_shown));
  }
  cmd->callback([cmd, given] {
    tasks::RunOptions o = run_options(*cmd, *given);
    if (!o.resume && o.out.empty()) o.out = tasks::default_run_folder(o);
    train_until_done_or_stopped(o);  // run_training refuses a folder holding a run: see --force
  });
}

}  // namespace hnn::app
