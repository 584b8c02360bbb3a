#include "tasks/run.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "autodiff/parallel.h"
#include "tasks/data/file_digest.h"
#include "tasks/experiments/registry.h"
#include "tasks/options/fit_options.h"
#include "tasks/options/model_settings.h"
#include "tasks/report/json_values.h"
#include "tasks/train/checkpoint.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void check_train_config(const TrainConfig& c, const FitConfig& fit) {
  HNN_TASKS_CHECK(c.steps > 0 || !fit.steps(), "--steps must be positive, got {}", c.steps);
  HNN_TASKS_CHECK(c.batch_size >= 0, "--batch must be >= 0, got {}", c.batch_size);
  HNN_TASKS_CHECK(c.learning_rate > 0 && std::isfinite(c.learning_rate),
                  "--lr must be a positive finite number, got {}", c.learning_rate);
  HNN_TASKS_CHECK(c.weight_decay >= 0 && std::isfinite(c.weight_decay),
                  "weight decay must be a finite number >= 0, got {}", c.weight_decay);
  HNN_TASKS_CHECK(!c.hidden.empty(), "--hidden needs at least one width");
  for (int w : c.hidden) {
    HNN_TASKS_CHECK(w > 0 && w <= kMaxWidth, "--hidden widths must be 1..{}, got {}", kMaxWidth, w);
    HNN_TASKS_CHECK(w <= kMaxAdamWidth || fit.samples(),
                    "--hidden {} is wider than Adam trains ({} at most); --fit sampled takes up "
                    "to {}",
                    w, kMaxAdamWidth, kMaxWidth);
  }
}

TrainConfig train_config(const Task& task, const RunOptions& o, const FitConfig& fit) {
  TrainConfig c = task.train_config();
  if (o.preset == Preset::kLean) c.hidden = task.lean_hidden();
  // One sampled layer, measured better than two of the paper's widths (docs/sampled.md).
  if (!fit.steps() && o.preset == Preset::kPaper) c.hidden = {kSampledWidth};
  if (!fit.steps()) c.steps = 0;  // a sampled fit takes none: its runs record so
  if (o.steps) c.steps = *o.steps;
  if (o.batch_size) c.batch_size = *o.batch_size;
  if (o.hidden) c.hidden = *o.hidden;
  if (o.learning_rate) c.learning_rate = *o.learning_rate;
  if (o.weight_decay) c.weight_decay = *o.weight_decay;
  if (o.lr_schedule) c.lr_schedule = *o.lr_schedule;
  if (o.optimizer) c.optimizer = *o.optimizer;
  return c;
}

// Why a model that needs velocities does not fit a task, and which tasks it fits.
std::string needs_velocities_note(nn::ModelKind model) {
  if (!nn::needs_velocities(model)) return "";
  std::vector<std::string> fits;
  for (const std::string& name : task_names()) {
    const std::vector<nn::ModelKind> models = make_task(name)->models();
    if (std::find(models.begin(), models.end(), model) != models.end()) fits.push_back(name);
  }
  return fmt::format(
      ": an {} learns from coordinates and their velocities, which "
      "this task's states are not (tasks that have them: {})",
      nn::to_string(model), fmt::join(fits, ", "));
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

LoopOptions loop_options(const RunOptions& o, const RunSettings& s, const RunFolder& folder) {
  // Steps, schedule and loss-curve interval: the run's own (with_train_config, tasks/task.h).
  return {.quiet = o.quiet,
          .label = fmt::format("{} {}", s.task, nn::to_string(s.model)),
          .checkpoint_dir = folder.checkpoint_dir(),
          .checkpoint_every = o.checkpoint_every.value_or(0),
          .resume = o.resume,
          .checkpoint_steps = o.continuing ? o.continued_from.back() : 0,
          .run_settings = s.to_json(),
          .stop = o.stop};
}

// The run's data file where the settings name it, before it is read: one line when it is
// missing, or (a recorded SHA-256) when it is another file than the run's.
void check_own_data(const RunSettings& s, const fs::path& run_dir) {
  if (s.data_file.empty()) return;
  std::error_code ec;
  HNN_TASKS_CHECK(fs::is_regular_file(s.data_file, ec),
                  "the data file '{}' of run '{}' is missing (moved?): give its place with "
                  "--data FILE",
                  s.data_file, run_dir.string());
  if (s.data_sha256.empty()) return;  // a run from before the checksum
  const std::string sha = file_sha256(s.data_file);
  HNN_TASKS_CHECK(sha == s.data_sha256,
                  "'{}' is not the data file of run '{}' (its SHA-256 is {}..., the run's {}...): "
                  "give the run's own file with --data FILE",
                  s.data_file, run_dir.string(), sha.substr(0, 12), s.data_sha256.substr(0, 12));
}

// The data file as a run records it: by absolute path, and its SHA-256 (kept when recorded).
void record_data_file(RunSettings& s) {
  if (s.data_file.empty()) return;
  s.data_file = fs::absolute(s.data_file).lexically_normal().string();
  if (s.data_sha256.empty()) s.data_sha256 = file_sha256(s.data_file);
}

bool holds_run(const RunFolder& folder) {
  std::error_code ec;
  return fs::exists(folder.file("metrics.json"), ec) || fs::exists(folder.params_file(), ec) ||
         fs::exists(folder.checkpoint_dir() / "state.json", ec);
}

// Whether `dir` holds nothing but a checkpoint/ folder without state.json: what a run killed
// before its first checkpoint committed leaves, nothing to keep (Note [Checkpoint commit] in
// tasks/train/checkpoint.h: the next checkpoint removes it).
bool only_uncommitted_checkpoint(const RunFolder& folder) {
  for (const fs::directory_entry& entry : fs::directory_iterator(folder.path()))
    if (entry.path().filename() != folder.checkpoint_dir().filename()) return false;
  return !fs::exists(folder.checkpoint_dir() / "state.json");
}

// "'a.txt', 'b'" (the first few entries of a folder), for a message.
std::string some_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    names.push_back("'" + entry.path().filename().string() + "'");
    if (names.size() == 3) break;
  }
  return fmt::format("{}", fmt::join(names, ", "));
}

// The run's folder, made (or, with --force, emptied) once nothing can fail before training.
void make_run_folder(const RunOptions& o, const RunFolder& folder) {
  if (o.force && !o.resume && fs::is_directory(o.out)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(o.out))
      fs::remove_all(entry.path());
  }
  folder.create();
}

// The run's evaluation and its time, eval_seconds, whatever the task: measured here, around all
// of it (a field task's held-out stretches, timed inside it before, were left out: a 200-step
// two-body run's summary said 1.5 s of evaluation, 5.5 s measured around all of it).
json timed_evaluation(const TaskRun& run, const RunFolder* folder) {
  const auto start = std::chrono::steady_clock::now();
  json metrics = run.evaluate(folder);
  metrics["eval_seconds"] = seconds_since(start);
  return metrics;
}

// The metrics of a trained run, with its settings: metrics.json's content.
json run_metrics(const TaskRun& run, const RunFolder& folder, const TrainResult& trained,
                 const RunSettings& settings) {
  json metrics = timed_evaluation(run, &folder);
  metrics["train_seconds"] = trained.seconds;
  metrics["curve_seconds"] = trained.curve_seconds;
  if (!trained.fit.is_null()) metrics["fit"] = trained.fit;
  metrics["final_batch_loss"] =
      number(trained.curve.empty() ? NAN : trained.curve.back().train_loss);
  metrics.update(settings.to_json());
  metrics["warnings"] = run_warnings(trained.curve, metrics);
  return metrics;
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
    const std::string reason = task.refusal_reason(o.model);
    throw Error(fmt::format("task '{}' does not train a {} model (its models: {}){}", task.name(),
                            nn::to_string(o.model), fmt::join(names, ", "),
                            reason.empty() ? needs_velocities_note(o.model) : reason));
  }
  const FitConfig fit = fit_config(o.task_settings, task.name());
  check_fit_model(fit, o.model, task.name());
  given_velocities(o.task_settings, o.model, fit.samples(), velocity_state(task), task.name());
  learned_masses(o.task_settings, o.model, task.name());
  RunSettings s{.task = task.name(),
                .model = o.model,
                .seed = o.seed,
                .dtype = o.dtype.value_or(task.default_dtype()),
                .preset = o.preset,
                .threads = o.threads,
                .train = train_config(task, o, fit),
                .data_file = o.data_file,
                .data_sha256 = o.data_sha256,
                .continued_from = o.continued_from,
                .task_settings = o.task_settings,
                .loss = rollout_loss_config(o.task_settings, task.name(), task.default_loss()),
                .fit = fit};
  check_train_config(s.train, s.fit);
  HNN_TASKS_CHECK(!s.loss.rollout || s.fit.steps(),
                  "{}: --loss rollout does not apply to --fit sampled (the last layer is solved "
                  "on dx/dt targets; --fit sampled+adam fine-tunes through the integrator)",
                  task.name());
  return s;
}

RunSettings validate(const RunOptions& o) {
  const RunSettings s = resolve(*make_task(o.task), o);
  if (!s.fit.steps()) check_sampled_options(o);
  if (s.fit.samples()) check_solver_options(s.fit, o.task_settings, s.task);
  HNN_TASKS_CHECK(!o.checkpoint_every || *o.checkpoint_every > 0,
                  "--checkpoint-every must be positive, got {}", o.checkpoint_every.value_or(0));
  HNN_TASKS_CHECK(!o.out.empty(), "an output folder is required");
  HNN_TASKS_CHECK(!std::filesystem::exists(o.out) || std::filesystem::is_directory(o.out),
                  "--out '{}' is a file, not a folder", o.out.string());
  return s;
}

json run_training(const RunOptions& o) {
  RunSettings settings = validate(o);
  if (o.resume) {
    check_own_data(settings, o.out);
  } else {
    check_new_run_folder(o.out, o.force);
  }
  ad::set_num_threads(settings.threads);  // the fused kernels' row blocks
  const std::unique_ptr<Task> task = make_task(settings.task);
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<TaskRun> run = task->open(settings);
  const double data_seconds = seconds_since(start);
  record_data_file(settings);
  const RunFolder folder(o.out);
  LoopOptions loop = loop_options(o, settings, folder);
  // Resumed, the weights come from the checkpoint (not sampled again): the run keeps its fit's
  // report, from metrics.json or the checkpoint, and its next checkpoints carry it on.
  const json sampled_before = o.resume ? recorded_fit(o.out) : json();
  if (!sampled_before.is_null()) loop.run_settings["fit"] = sampled_before;
  // After the data, and after a sampled fit's sampling (FieldTraining calls before_steps): bad
  // data or a fit that fails (too wide, singular) leave the folder as it was, or no folder.
  bool made = false;
  const auto make_folder = [&] {
    if (!std::exchange(made, true)) make_run_folder(o, folder);
  };
  if (settings.fit.samples() && !o.resume)
    loop.before_steps = make_folder;
  else
    make_folder();
  TrainResult trained = run->train(loop);
  make_folder();  // where the task did not call before_steps
  if (trained.fit.is_null()) trained.fit = sampled_before;
  run->save(folder.params_file());
  json metrics = run_metrics(*run, folder, trained, settings);
  // A run that learns in standardised units (a data run) watched its loss in them: the columns
  // say so, as metrics.json's keys do. A pure sampled fit takes no steps and has no curve.
  if (settings.fit.steps())
    folder.write_loss_curve(trained.curve,
                            metrics.contains("test_loss_standardised") ? "_standardised" : "");
  metrics["data_seconds"] = data_seconds;
  folder.write_metrics(metrics);
  return metrics;
}

fs::path default_run_folder(const RunOptions& o) {
  fs::path dir = fs::path("runs") / o.task;
  if (!o.data_file.empty()) dir /= fs::path(o.data_file).stem();
  return dir / nn::to_string(o.model);
}

LoadedRun load_run(const fs::path& run_dir, const std::string& data_file, DataFileUse use) {
  const RunFolder folder(run_dir);
  RunOptions options =
      options_from_json(folder.read_metrics(), "'" + folder.file("metrics.json").string() + "'");
  if (!data_file.empty()) options.data_file = data_file;
  if (use == DataFileUse::kOther) options.data_sha256.clear();  // recorded: the other file's
  LoadedRun loaded;
  loaded.task = make_task(options.task);
  loaded.settings = resolve(*loaded.task, options);
  check_own_data(loaded.settings, run_dir);
  record_data_file(loaded.settings);
  ad::set_num_threads(loaded.settings.threads);
  loaded.run = loaded.task->open(loaded.settings);
  loaded.run->load(folder.params_file());
  return loaded;
}

json evaluate_run(const fs::path& run_dir, const std::string& data_file, bool write_files) {
  const LoadedRun loaded =
      load_run(run_dir, data_file, data_file.empty() ? DataFileUse::kRunsOwn : DataFileUse::kOther);
  const RunFolder folder(run_dir);
  json metrics = timed_evaluation(*loaded.run, write_files ? &folder : nullptr);
  metrics.update(loaded.settings.to_json());
  // How the weights were fitted, as trained: the summary says so beside the new figures.
  if (json fit = recorded_fit(run_dir); !fit.is_null()) metrics["fit"] = std::move(fit);
  metrics["warnings"] = run_warnings({}, metrics);
  return metrics;
}

RunOptions resume_options(const fs::path& run_dir, std::optional<int> steps) {
  check_not_sampled_run(run_dir);
  const fs::path dir = RunFolder(run_dir).checkpoint_dir();
  const TrainState state = read_train_state(dir);
  RunOptions o = options_from_json(state.run, fmt::format("the checkpoint in '{}'", dir.string()));
  o.out = run_dir;
  o.resume = true;
  if (!steps || *steps == state.total_steps) return o;
  const std::string run = run_dir.string();
  HNN_TASKS_CHECK(state.step >= state.total_steps,
                  "'{}' holds an unfinished run (step {} of {}): --steps continues a finished run; "
                  "finish this one first with `hnn train --resume {}`",
                  run, state.step, state.total_steps, run);
  HNN_TASKS_CHECK(*steps > state.total_steps,
                  "--steps {} is fewer than the {} steps run '{}' was trained for: --resume with "
                  "--steps continues a run to more steps",
                  *steps, state.total_steps, run);
  // A cosine schedule is a function of the step and the total: continued, the rate would jump
  // back up from ~0, unlike any run of `steps` from the start.
  HNN_TASKS_CHECK(o.lr_schedule != LrSchedule::kCosine,
                  "run '{}' decayed its learning rate to 0 over its {} steps (--lr-schedule "
                  "cosine): continuing it would start the decay again; train a new run with "
                  "--steps {}",
                  run, state.total_steps, *steps);
  o.continued_from.push_back(int(state.total_steps));
  o.steps = *steps;
  o.continuing = true;
  return o;
}

void check_no_unfinished_run(const fs::path& run_dir) {
  const fs::path dir = RunFolder(run_dir).checkpoint_dir();
  if (!fs::exists(dir / "state.json")) return;
  const TrainState state = read_train_state(dir);
  HNN_TASKS_CHECK(state.step >= state.total_steps,
                  "'{}' holds an unfinished run (step {} of {}): continue it with `hnn train "
                  "--resume {}`, or replace it with --force, or choose another --out",
                  run_dir.string(), state.step, state.total_steps, run_dir.string());
}

void check_new_run_folder(const fs::path& out, bool force) {
  std::error_code ec;
  if (!fs::is_directory(out, ec) || fs::is_empty(out, ec)) return;  // validate refuses a file
  const RunFolder folder(out);
  if (only_uncommitted_checkpoint(folder)) return;
  const std::string dir = out.string();
  if (!holds_run(folder)) {
    throw Error(fmt::format("'{}' is not empty and holds no run ({}){}: choose another --out", dir,
                            some_entries(out), force ? ", so --force does not clear it" : ""));
  }
  if (force) return;
  check_no_unfinished_run(out);
  throw Error(
      fmt::format("'{}' already holds a run: replace it with --force (its files are "
                  "removed), or choose another --out",
                  dir));
}

}  // namespace hnn::tasks
