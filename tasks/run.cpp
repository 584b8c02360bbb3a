#include "tasks/run.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "autodiff/parallel.h"
#include "tasks/experiments/registry.h"
#include "tasks/report/json_values.h"
#include "tasks/train/checkpoint.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

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
          .run_settings = s.to_json(),
          .stop = o.stop};
}

// The metrics of a trained run, with its settings: metrics.json's content.
json run_metrics(const TaskRun& run, const RunFolder& folder, const TrainResult& trained,
                 const RunSettings& settings) {
  json metrics = run.evaluate(&folder);
  metrics["train_seconds"] = trained.seconds;
  metrics["final_batch_loss"] =
      number(trained.curve.empty() ? NAN : trained.curve.back().train_loss);
  metrics.update(settings.to_json());
  metrics["warnings"] = run_warnings(trained.curve, metrics);
  return metrics;
}

// A point's test loss, or its train loss where there is no test split.
double curve_loss(const CurvePoint& p) {
  return std::isnan(p.test_loss) ? p.train_loss : p.test_loss;
}

}  // namespace

std::vector<std::string> run_warnings(const std::vector<CurvePoint>& curve, const json& metrics) {
  std::vector<std::string> warnings;
  if (curve.size() >= 2) {
    const CurvePoint &first = curve.front(), &last = curve.back();
    const std::string which = std::isnan(first.test_loss) ? "training" : "test";
    if (!(curve_loss(last) < curve_loss(first))) {
      warnings.push_back(fmt::format(
          "the {} loss did not fall: {:.3g} at step {}, {:.3g} at the last step ({}); the run "
          "ended no better than it started (a smaller --lr may help)",
          which, curve_loss(first), first.step, curve_loss(last), last.step));
    }
  }
  const auto r2 = metrics.find("test_r2");
  if (r2 != metrics.end() && r2->is_number() && r2->get<double>() < kLowR2) {
    warnings.push_back(fmt::format(
        "the test R^2 is {:.3g}, below {}: the model explains almost none of the spread of the "
        "test dx/dt",
        r2->get<double>(), kLowR2));
  }
  return warnings;
}

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
                .task_settings = o.task_settings,
                .loss = rollout_loss_config(o.task_settings, task.name())};
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

json run_training(const RunOptions& o) {
  const RunSettings settings = validate(o);
  ad::set_num_threads(settings.threads);  // the fused kernels' row blocks
  const std::unique_ptr<Task> task = make_task(settings.task);
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<TaskRun> run = task->open(settings);
  const double data_seconds = seconds_since(start);
  const RunFolder folder(o.out);
  folder.create();  // after the data: bad data leave no folder behind
  const TrainResult trained = run->train(loop_options(o, settings, folder));
  run->save(folder.params_file());
  folder.write_loss_curve(trained.curve);
  json metrics = run_metrics(*run, folder, trained, settings);
  metrics["data_seconds"] = data_seconds;
  folder.write_metrics(metrics);
  return metrics;
}

LoadedRun load_run(const fs::path& run_dir, const std::string& data_file) {
  const RunFolder folder(run_dir);
  RunOptions options =
      options_from_json(folder.read_metrics(), "'" + folder.file("metrics.json").string() + "'");
  if (!data_file.empty()) options.data_file = data_file;
  LoadedRun loaded;
  loaded.task = make_task(options.task);
  loaded.settings = resolve(*loaded.task, options);
  ad::set_num_threads(loaded.settings.threads);
  loaded.run = loaded.task->open(loaded.settings);
  loaded.run->load(folder.params_file());
  return loaded;
}

json evaluate_run(const fs::path& run_dir, const std::string& data_file, bool write_files) {
  const LoadedRun loaded = load_run(run_dir, data_file);
  const RunFolder folder(run_dir);
  json metrics = loaded.run->evaluate(write_files ? &folder : nullptr);
  metrics.update(loaded.settings.to_json());
  metrics["warnings"] = run_warnings({}, metrics);
  return metrics;
}

fs::path write_rollout(const fs::path& run_dir, const RolloutRequest& request,
                       const fs::path& out) {
  const LoadedRun loaded = load_run(run_dir);
  const fs::path path =
      out.empty() ? run_dir / fmt::format("rollout_{}.csv", request.integrator) : out;
  RunFolder(path.parent_path().empty() ? "." : path.parent_path())
      .write_text(path.filename().string(), loaded.run->rollout_csv(request));
  return path;
}

json reversibility(const fs::path& run_dir, const ReversibilityOptions& options) {
  const LoadedRun loaded = load_run(run_dir);
  ReversibilityOptions o = options;
  if (o.t_end <= 0) o.t_end = loaded.run->rollout_span();
  json result =
      measure_reversibility(loaded.run->dynamics(), loaded.run->rollout_states(o.trajectories), o);
  result.update({{"task", loaded.settings.task},
                 {"model", nn::to_string(loaded.settings.model)},
                 {"space", loaded.run->space()}});
  RunFolder(run_dir).write_text("reversibility.json", result.dump(2) + "\n");
  return result;
}

RunOptions resume_options(const fs::path& run_dir) {
  const fs::path dir = RunFolder(run_dir).checkpoint_dir();
  RunOptions o = options_from_json(read_train_state(dir).run,
                                   fmt::format("the checkpoint in '{}'", dir.string()));
  o.out = run_dir;
  o.resume = true;
  return o;
}

void check_no_unfinished_run(const fs::path& run_dir) {
  const fs::path dir = RunFolder(run_dir).checkpoint_dir();
  if (!fs::exists(dir / "state.json")) return;
  const TrainState state = read_train_state(dir);
  HNN_TASKS_CHECK(state.step >= state.total_steps,
                  "'{}' holds an unfinished run (step {} of {}): continue it with `hnn train "
                  "--resume {}`, or choose another --out, or delete '{}'",
                  run_dir.string(), state.step, state.total_steps, run_dir.string(), dir.string());
}

}  // namespace hnn::tasks
