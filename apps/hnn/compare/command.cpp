// `hnn compare`: every (task, model, loss) of a study for N seeds, run through the sweep engine
// (the same run folders, Dask driver, resume and lock as `hnn sweep`), then a table of ours beside
// the peers' published numbers (apps/hnn/compare/compare_report.py, called by the driver at the
// end). Which pairs run is decided by hnn itself: each is expanded and checked as `hnn sweep`
// checks a run (tasks::validate), and a pair that fails is a "skipped: <reason>" row of the table.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <fstream>
#include <set>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "apps/hnn/compare/studies.h"
#include "apps/hnn/sweep/keys.h"
#include "apps/hnn/sweep/launch.h"
#include "tasks/experiments/registry.h"
#include "tasks/studies/published.h"
#include "tasks/task.h"
#include "tasks/train/fit_method.h"

namespace hnn::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

/// --quick: steps of every run (a smoke run of the whole study).
constexpr int kQuickSteps = 100;

struct CompareOptions {
  std::vector<std::string> tasks, models, losses, fits;
  int seeds = 3, steps = 0;
  std::string out, study = "default";
  bool quick = false, list = false;
  sweep::LaunchOptions launch;
  std::string command;  // the command line, for the report
};

// One row of the table: a (task, model, loss) at its protocol's keys, and its runs, or why it
// does not run.
struct Row {
  std::string task, model, loss, fit;
  ordered_json keys = ordered_json::object();
  std::string headline;
  std::vector<std::string> metrics;
  std::string skipped;  // "": runs
  std::vector<std::string> runs;
};

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

void check_names(const std::vector<std::string>& given, const std::vector<std::string>& known,
                 const char* option, const char* what) {
  for (const std::string& name : given) {
    if (!contains(known, name)) {
      throw std::invalid_argument(fmt::format("compare: {}: unknown {} '{}' (known: {})", option,
                                              what, name, fmt::join(known, ", ")));
    }
  }
}

// The loss a task trains with unless told (Task::default_loss): rows of it leave "loss" out, so
// their run folders keep the names they had. An unknown task (a skipped row) trains none.
std::string default_loss(const std::string& task) {
  try {
    return tasks::make_task(task)->default_loss().rollout ? "rollout" : "derivative";
  } catch (const tasks::Error&) {
    return "derivative";
  }
}

// The study's groups: --tasks x --models x --loss, or the --study narrowed to the --models and
// --loss given.
std::vector<Group> study(const CompareOptions& o) {
  if (!o.tasks.empty()) {
    const std::vector<std::string> models = o.models.empty() ? tasks::model_names() : o.models;
    if (!o.losses.empty()) return {crossed(o.tasks, models, o.losses)};
    std::vector<Group> groups;  // each task at the loss it trains with unless told
    for (const std::string& task : o.tasks)
      groups.push_back(crossed({task}, models, {default_loss(task)}));
    return groups;
  }
  std::vector<Group> groups;
  for (Group g : named_study(o.study)) {
    const auto keep = [](std::vector<std::string>& names, const std::vector<std::string>& only) {
      if (only.empty()) return;
      std::erase_if(names, [&](const std::string& n) { return !contains(only, n); });
    };
    keep(g.models, o.models);
    keep(g.losses, o.losses);
    if (!g.models.empty() && !g.losses.empty()) groups.push_back(g);
  }
  if (groups.empty())
    throw std::invalid_argument(
        fmt::format("compare: the {} study has no runs of those --models/--loss", o.study));
  return groups;
}

// The sweep keys of Adam's steps (tasks/options/fit_options.h, adam_option_given): a protocol's,
// left out of a row fitted by sampling alone, which takes no steps.
constexpr std::array<const char*, 6> kAdamKeys = {"steps",       "batch",     "lr",
                                                  "lr-schedule", "optimizer", "checkpoint-every"};

bool takes_steps(const std::string& fit) { return fit != "sampled"; }

// The sweep spec of one row: its task, model, loss and fit, and the seeds (and steps) of the
// study.
ordered_json row_spec(const Row& row, const CompareOptions& o) {
  ordered_json spec = ordered_json::object();
  spec["task"] = {row.task};
  spec["model"] = {row.model};
  ordered_json seeds = ordered_json::array();
  for (int s = 0; s < o.seeds; ++s) seeds.push_back(static_cast<unsigned long long>(s));
  spec["seed"] = seeds;
  for (const auto& [key, value] : row.keys.items()) spec[key] = ordered_json::array({value});
  if (o.steps > 0 && takes_steps(row.fit)) spec["steps"] = {o.steps};  // over the protocol's
  if (row.loss != default_loss(row.task)) spec["loss"] = {row.loss};
  if (row.fit != "adam") spec["fit"] = {row.fit};  // adam: hnn train's default
  return spec;
}

// "compare: run 'x/y/seed=0': why" or "compare: key 'loss': why" -> the why, as hnn said it.
std::string reason_of(std::string message) {
  const std::string prefix = "compare: ";
  if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
  if (message.rfind("run '", 0) == 0) {
    if (const auto end = message.find("': "); end != std::string::npos) message.erase(0, end + 3);
  }
  return message;
}

// Expands every row through the sweep's checks; the runs of those that pass make one plan.
sweep::SweepPlan expand_rows(std::vector<Row>& rows, const CompareOptions& o, const fs::path& out) {
  const std::vector<std::string> known_tasks = tasks::task_names(),
                                 known_models = tasks::model_names();
  sweep::SweepPlan plan;
  std::set<std::string> keys, names;
  for (Row& row : rows) {
    if (!contains(known_tasks, row.task)) {
      row.skipped = fmt::format("this hnn has no task '{}' yet (its tasks: {})", row.task,
                                fmt::join(known_tasks, ", "));
      continue;
    }
    if (!contains(known_models, row.model)) {
      row.skipped = fmt::format("this hnn has no model '{}' yet (its models: {})", row.model,
                                fmt::join(known_models, ", "));
      continue;
    }
    sweep::SweepPlan one;
    try {
      one = sweep::expand(row_spec(row, o), "compare", out);
    } catch (const std::invalid_argument& e) {
      row.skipped = reason_of(e.what());
      continue;
    }
    for (sweep::SweepRun& r : one.runs) {
      row.runs.push_back(r.name);
      if (names.insert(r.name).second) plan.runs.push_back(std::move(r));
    }
    keys.insert(one.keys.begin(), one.keys.end());
  }
  for (const tasks::TrainOption* k : sweep::key_table())
    if (keys.count(std::string(k->name))) plan.keys.emplace_back(k->name);
  return plan;
}

// Each group's rows, for each fit (a fit's rows after the previous fit's).
std::vector<Row> rows_of(const std::vector<Group>& groups, const std::vector<std::string>& fits) {
  std::vector<Row> rows;
  std::set<std::string> seen;
  for (const std::string& f : fits)
    for (const Group& g : groups)
      for (const std::string& t : g.tasks)
        for (const std::string& m : g.models)
          for (const std::string& l : g.losses) {
            Row row{t, m, l, f, g.keys, g.headline, g.metrics, "", {}};
            if (l == "rollout") row.keys.update(g.rollout_keys);
            if (!takes_steps(f))
              for (const char* key : kAdamKeys) row.keys.erase(key);
            // A pair twice is one row, unless at another protocol (the constrained study's
            // 2-chain at 10 trajectories beside its default).
            if (seen.insert(fmt::format("{}\n{}\n{}\n{}\n{}", t, m, l, f, row.keys.dump())).second)
              rows.push_back(std::move(row));
          }
  return rows;
}

// "hnn", or "hnn (sampled)" for a fit other than Adam.
std::string model_label(const Row& r) {
  return r.fit == "adam" ? r.model : fmt::format("{} ({})", r.model, r.fit);
}

json rows_json(const std::vector<Row>& rows) {
  json out = json::array();
  for (const Row& r : rows) {
    out.push_back({{"task", r.task},
                   {"model", r.model},
                   {"loss", r.loss},
                   {"fit", r.fit},
                   {"keys", json::parse(r.keys.dump())},
                   {"headline", r.headline.empty() ? json(nullptr) : json(r.headline)},
                   {"metrics", r.metrics},
                   {"runs", r.runs},
                   {"skipped", r.skipped.empty() ? json(nullptr) : json(r.skipped)}});
  }
  return out;
}

json compare_section(const std::vector<Row>& rows, const CompareOptions& o) {
  const fs::path file = tasks::published_path();
  const json peers_doc = tasks::read_published(file);
  std::vector<std::string> own_settings;  // tasks with rows at their own settings
  for (const Row& row : rows) {
    if (row.keys.empty() && !contains(own_settings, row.task)) own_settings.push_back(row.task);
  }
  // A number that holds only at a task's defaults (the HNN paper's Table 1) is a peer only of a
  // task the study runs at its defaults, in the study's order of tasks; the others follow.
  const auto defaults_only = [](const json& p) { return p.value("task_defaults_only", false); };
  json peers = json::array();
  for (const std::string& task : own_settings)
    for (const json& p : peers_doc["peers"])
      if (defaults_only(p) && p["task"] == task) peers.push_back(p);
  for (const json& p : peers_doc["peers"])
    if (!defaults_only(p)) peers.push_back(p);
  return {{"command", o.command},
          {"seeds", o.seeds},
          {"steps", o.steps > 0 ? json(o.steps) : json("each task's default")},
          {"peers_file", fs::absolute(file).lexically_normal().string()},
          {"headline", peers_doc.value("headline", json::object())},
          {"report_metrics", peers_doc.value("report_metrics", json::array({"test_loss"}))},
          {"geometric_metrics", peers_doc.value("geometric_metrics", json::array())},
          {"hnn_tasks", tasks::task_names()},
          {"rows", rows_json(rows)},
          {"peers", peers}};
}

void list_rows(const std::vector<Row>& rows) {
  for (const Row& r : rows) {
    const std::string keys = r.keys.empty() ? "" : " " + r.keys.dump();
    if (r.skipped.empty())
      fmt::print("{} {} {}{}: {} runs\n", r.task, model_label(r), r.loss, keys, r.runs.size());
    else
      fmt::print("{} {} {}{}: skipped: {}\n", r.task, model_label(r), r.loss, keys, r.skipped);
  }
}

void run_compare(CompareOptions o) {
  check_names(o.tasks, tasks::task_names(), "--tasks", "task");
  check_names(o.models, tasks::model_names(), "--models", "model");
  check_names(o.losses, tasks::loss_names(), "--loss", "loss");
  check_names(o.fits, tasks::fit_method_names(), "--fit", "fit");
  if (o.fits.empty()) o.fits = {"adam"};
  sweep::check_scheduler(o.launch.scheduler);
  if (o.quick && o.steps == 0) o.steps = kQuickSteps;
  const fs::path out = fs::absolute(o.out).lexically_normal();
  std::vector<Row> rows = rows_of(study(o), o.fits);
  if (o.steps > 0) {
    for (Row& row : rows) row.keys.erase("steps");  // --steps is every run's
  }
  const sweep::SweepPlan plan = expand_rows(rows, o, out);
  const json section = compare_section(rows, o);  // the peers file is checked before any run
  if (o.list) {
    list_rows(rows);
    return sweep::list_runs(plan, o.launch, out);
  }
  const fs::path report =
      sweep::shared_file("HNN_COMPARE_REPORT", "compare_report.py", HNN_COMPARE_REPORT_SOURCE);
  sweep::launch(plan, o.launch, out, o.command, "run",
                {{"compare", section}, {"report_module", report.string()}});
}

std::string command_line(int argc, char** argv) {
  std::string line = "hnn";
  for (int i = 1; i < argc; ++i) line += " " + sweep::shell_quote(argv[i]);
  return line;
}

}  // namespace

void add_compare_command(CLI::App& app, int argc, char** argv) {
  auto* cmd = app.add_subcommand(
      "compare",
      "Train every model family on the study's tasks for N seeds (through hnn sweep's engine) "
      "and table ours beside the peers' published numbers; see docs/compare.md");
  auto o = std::make_shared<CompareOptions>();
  o->command = command_line(argc, argv);
  auto* tasks_option =
      cmd->add_option("--tasks", o->tasks,
                      "Comma-separated tasks (default: the --study's, docs/compare.md)")
          ->delimiter(',');
  cmd->add_option("--study", o->study,
                  fmt::format("A named study, each task at its peer's protocol: {} (constrained: "
                              "Finzi et al.'s systems, 8,000 steps a run, hours in all)",
                              fmt::join(study_names(), ", ")))
      ->check(CLI::IsMember(study_names()))
      ->excludes(tasks_option)
      ->capture_default_str();
  cmd->add_option("--models", o->models,
                  "Comma-separated model families (default: every one hnn has)")
      ->delimiter(',');
  cmd->add_option("--loss", o->losses,
                  "Comma-separated losses: derivative, rollout (default: with --tasks, each "
                  "task's own; else the --study's)")
      ->delimiter(',');
  cmd->add_option("--fit", o->fits,
                  "Comma-separated fits, an axis of the study: adam, sampled, sampled+adam "
                  "(default adam; a sampled row takes no steps, and the table names it like "
                  "'hnn (sampled)')")
      ->delimiter(',');
  cmd->add_option("--seeds", o->seeds, "Seeds per task, model and loss (0..N-1)")
      ->check(integer_in(1, 1000))
      ->capture_default_str();
  cmd->add_option("--steps", o->steps, "Training steps of every run (default: each task's)")
      ->check(positive_integer());
  cmd->add_flag("--quick", o->quick,
                fmt::format("A smoke run: {} steps a run unless --steps", kQuickSteps));
  cmd->add_option("--out", o->out, "Folder: runs/, results.csv, compare.md/.json, the chart")
      ->required();
  sweep::add_launch_options(*cmd, o->launch);
  cmd->add_flag("--list", o->list,
                "Print each task, model and loss (its runs, or why it is skipped) and each run's "
                "hnn train command; run nothing");
  cmd->callback([o] { run_compare(*o); });
}

}  // namespace hnn::app
