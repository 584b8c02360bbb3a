#include "tasks/run.h"

#include <Eigen/Core>
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "autodiff/parallel.h"
#include "nn/checkpoint.h"
#include "nn/hnn.h"
#include "tasks/evaluate.h"
#include "tasks/files.h"
#include "tasks/pixel_pendulum.h"
#include "tasks/task_library.h"
#include "tasks/train_checkpoint.h"
#include "tasks/trainer.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// JSON has no NaN: a missing number is null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TrainConfig resolve_config(const Task& task, const RunOptions& o) {
  TrainConfig config = train_config(task, o.preset);
  if (o.steps) config.steps = *o.steps;
  if (o.batch_size) config.batch_size = *o.batch_size;
  if (o.hidden) config.hidden = *o.hidden;
  if (o.learning_rate) config.learning_rate = *o.learning_rate;
  return config;
}

std::unique_ptr<Task> open_task(const std::string& name, const std::string& data_file) {
  std::unique_ptr<Task> task = make_task(name);
  if (!data_file.empty()) task->set_data_file(data_file);
  return task;
}

nn::DynamicsConfig model_config(const std::string& model, Eigen::Index dim,
                                const std::vector<int>& hidden) {
  nn::DynamicsConfig config;
  config.model = nn::parse_model_kind(model);
  config.dim = dim;
  config.hidden.assign(hidden.begin(), hidden.end());
  nn::validate(config);
  return config;
}

std::string loss_curve_csv(const TrainResult& result) {
  std::string csv = "step,train_loss,test_loss\n";
  for (const CurvePoint& p : result.curve)
    csv += fmt::format("{},{:.9g},{:.9g}\n", p.step, p.train_loss, p.test_loss);
  return csv;
}

std::string rollout_csv(const Rollouts& r) {
  const Eigen::Index dim = r.truth.empty() ? 0 : r.truth[0].cols();
  std::string csv = "traj,t";
  for (const char* which : {"true", "pred"})
    for (Eigen::Index k = 0; k < dim; ++k) csv += fmt::format(",{}_{}", which, k);
  csv += ",true_energy,pred_energy,learned_h\n";
  const auto cell = [](double v) { return std::isfinite(v) ? fmt::format("{:.12g}", v) : ""; };
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    for (std::size_t k = 0; k < r.t.size(); ++k) {
      const Eigen::Index row = Eigen::Index(k), traj = Eigen::Index(i);
      csv += fmt::format("{},{:.9g}", i, r.t[k]);
      for (Eigen::Index c = 0; c < dim; ++c) csv += "," + cell(r.truth[i](row, c));
      for (Eigen::Index c = 0; c < dim; ++c) csv += "," + cell(r.pred[i](row, c));
      csv += "," + cell(r.true_energy(traj, row)) + "," + cell(r.pred_energy(traj, row)) + ",";
      if (r.learned_h.size() > 0) csv += cell(r.learned_h(traj, row));
      csv += "\n";
    }
  }
  return csv;
}

// Losses and rollouts of a trained model (always in double: a float model is cast, so the
// rollout integrator's tolerance is not limited by float rounding of the field).
json evaluate_model(const Task& task, const Dataset& data, const nn::DynamicsModel<double>& model,
                    std::uint64_t seed, const fs::path& out, bool write_files) {
  const auto start = std::chrono::steady_clock::now();
  const nn::MeanStderr train = loss_stats(model, data.train_x, data.train_dxdt);
  const nn::MeanStderr test = loss_stats(model, data.test_x, data.test_dxdt);
  std::mt19937_64 rng(seed + 1);  // rollout states: independent of the training data's draws
  const Batch x0 = task.rollout_states(data, rng);
  const Rollouts rollouts = make_rollouts(task, model, x0, task.rollout_config());
  const nn::MeanStderr energy = energy_mse(rollouts);
  json m = {{"train_loss", number(train.mean)},  {"train_loss_se", number(train.std_error)},
            {"test_loss", number(test.mean)},    {"test_loss_se", number(test.std_error)},
            {"energy_mse", number(energy.mean)}, {"energy_mse_se", number(energy.std_error)},
            {"n_rollouts", energy.count},        {"rollout_failures", rollouts.failures},
            {"n_train", data.train_x.rows()},    {"n_test", data.test_x.rows()}};
  m["eval_seconds"] = seconds_since(start);
  if (write_files) write_file_atomic(out / "rollout.csv", rollout_csv(rollouts));
  return m;
}

// What `hnn train --resume` needs to rebuild the run: the options with every default resolved.
json run_settings(const Task& task, const RunOptions& o, const TrainConfig& config) {
  return {{"task", task.name()},
          {"model", o.model},
          {"seed", o.seed},
          {"dtype", o.dtype},
          {"preset", o.preset},
          {"threads", o.threads},
          {"steps", config.steps},
          {"batch_size", config.batch_size},
          {"hidden", config.hidden},
          {"learning_rate", config.learning_rate},
          {"data_file", o.data_file}};
}

template <typename T>
json train_and_evaluate(const Task& task, const Dataset& data, const RunOptions& o,
                        const TrainConfig& config) {
  std::mt19937_64 init_rng(o.seed);
  const nn::DynamicsConfig model_cfg = model_config(o.model, data.train_x.cols(), config.hidden);
  std::unique_ptr<nn::DynamicsModel<T>> model = nn::make_model<T>(model_cfg, init_rng);
  TrainHooks hooks;
  hooks.quiet = o.quiet;
  hooks.label = task.name() + " " + o.model;
  hooks.checkpoint_dir = checkpoint_dir(o.out);
  hooks.checkpoint_every = o.checkpoint_every.value_or(0);
  hooks.resume = o.resume;
  hooks.run_settings = run_settings(task, o, config);
  hooks.stop = o.stop;
  const TrainResult trained = train_model<T>(*model, data, config, o.seed, hooks);
  nn::save_parameters(o.out / "params.bin", *model);
  write_file_atomic(o.out / "loss_curve.csv", loss_curve_csv(trained));
  const auto model_d = nn::cast_model<double>(*model);
  json metrics = evaluate_model(task, data, *model_d, o.seed, o.out, true);
  metrics["train_seconds"] = trained.seconds;
  metrics["final_batch_loss"] =
      number(trained.curve.empty() ? NAN : trained.curve.back().train_loss);
  return metrics;
}

// "200-200" (metrics.json's form) -> {200, 200}; throws Error on anything else.
std::vector<int> parse_widths(const std::string& text) {
  std::vector<int> widths;
  std::stringstream in(text);
  for (std::string w; std::getline(in, w, '-');) {
    int width = 0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), width);
    HNN_TASKS_CHECK(
        ec == std::errc() && end == w.data() + w.size() && width > 0 && width <= kMaxWidth,
        "hidden '{}' is not widths of 1..{} joined by '-' (like 200-200)", text, kMaxWidth);
    widths.push_back(width);
  }
  HNN_TASKS_CHECK(!widths.empty(), "hidden '{}' names no widths", text);
  return widths;
}

std::string join(const std::vector<int>& v) {
  std::string s;
  for (int x : v) s += (s.empty() ? "" : "-") + std::to_string(x);
  return s;
}

}  // namespace

void validate(const RunOptions& o) {
  make_task(o.task);  // throws on an unknown task
  nn::parse_model_kind(o.model);
  HNN_TASKS_CHECK(o.dtype == "float" || o.dtype == "double",
                  "--dtype must be float or double, got '{}'", o.dtype);
  const std::vector<std::string> presets = preset_names();
  HNN_TASKS_CHECK(std::find(presets.begin(), presets.end(), o.preset) != presets.end(),
                  "--preset must be paper or lean, got '{}'", o.preset);
  HNN_TASKS_CHECK(o.threads >= 1 && o.threads <= 256, "--threads must be 1..256, got {}",
                  o.threads);
  HNN_TASKS_CHECK(!o.steps || *o.steps > 0, "--steps must be positive, got {}", *o.steps);
  HNN_TASKS_CHECK(!o.batch_size || *o.batch_size >= 0, "--batch must be >= 0, got {}",
                  *o.batch_size);
  HNN_TASKS_CHECK(!o.learning_rate || (*o.learning_rate > 0 && std::isfinite(*o.learning_rate)),
                  "--lr must be a positive finite number, got {}", o.learning_rate.value_or(0));
  if (o.hidden) {
    HNN_TASKS_CHECK(!o.hidden->empty(), "--hidden needs at least one width");
    for (int w : *o.hidden) {
      HNN_TASKS_CHECK(w > 0 && w <= kMaxWidth, "--hidden widths must be 1..{}, got {}", kMaxWidth,
                      w);
    }
  }
  HNN_TASKS_CHECK(!o.checkpoint_every || *o.checkpoint_every > 0,
                  "--checkpoint-every must be positive, got {}", o.checkpoint_every.value_or(0));
  HNN_TASKS_CHECK(!o.out.empty(), "an output folder is required");
  HNN_TASKS_CHECK(!fs::exists(o.out) || fs::is_directory(o.out),
                  "--out '{}' is a file, not a folder", o.out.string());
}

json run_training(const RunOptions& o) {
  validate(o);
  if (o.task == pixel::kTaskName) return pixel::run_pixel_training(o);  // frames, not fields
  ad::set_num_threads(o.threads);  // the fused kernels' row blocks
  const std::unique_ptr<Task> task = open_task(o.task, o.data_file);
  const TrainConfig config = resolve_config(*task, o);
  const auto start = std::chrono::steady_clock::now();
  const Dataset data = task->build_dataset(o.seed);
  const double data_seconds = seconds_since(start);
  // Checked before the run folder exists: a bad batch size leaves nothing behind.
  HNN_TASKS_CHECK(config.batch_size <= data.train_x.rows(),
                  "--batch {} is larger than the training set ({} rows)", config.batch_size,
                  data.train_x.rows());
  fs::create_directories(o.out);
  json metrics = o.dtype == "float" ? train_and_evaluate<float>(*task, data, o, config)
                                    : train_and_evaluate<double>(*task, data, o, config);
  metrics.update({{"task", task->name()},
                  {"model", o.model},
                  {"seed", o.seed},
                  {"steps", config.steps},
                  {"batch_size", config.batch_size},
                  {"hidden", join(config.hidden)},
                  {"preset", o.preset},
                  {"learning_rate", config.learning_rate},
                  {"weight_decay", config.weight_decay},
                  {"dtype", o.dtype},
                  {"threads", o.threads},
                  {"data_file", o.data_file},
                  {"data_seconds", data_seconds}});
  write_file_atomic(o.out / "metrics.json", metrics.dump(2) + "\n");
  return metrics;
}

LoadedRun load_run(const fs::path& run_dir, const std::string& data_file) {
  HNN_TASKS_CHECK(!pixel::is_pixel_run(run_dir),
                  "'{}' is a pixel-pendulum run: load it with pixel::load_pixel_run",
                  run_dir.string());
  const fs::path metrics_path = run_dir / "metrics.json";
  std::ifstream in(metrics_path);
  HNN_TASKS_CHECK(in.good(), "cannot read '{}': is '{}' a run folder of `hnn train`?",
                  metrics_path.string(), run_dir.string());
  json saved;
  try {
    saved = json::parse(in);
  } catch (const json::exception& e) {
    throw Error(fmt::format("'{}' is not valid JSON: {}", metrics_path.string(), e.what()));
  }
  LoadedRun run;
  RunOptions& o = run.options;
  try {
    o.task = saved.at("task");
    o.model = saved.at("model");
    HNN_TASKS_CHECK(saved.at("seed").is_number_unsigned(), "seed {} is not a non-negative integer",
                    saved.at("seed").dump());
    o.seed = saved.at("seed");
    o.dtype = saved.at("dtype");
    o.preset = saved.value("preset", "paper");
    o.hidden = parse_widths(saved.at("hidden").get<std::string>());
  } catch (const std::exception& e) {
    throw Error(
        fmt::format("'{}' does not hold a run's settings: {}", metrics_path.string(), e.what()));
  }
  o.data_file = data_file.empty() ? saved.value("data_file", "") : data_file;
  o.out = run_dir;
  run.task = open_task(o.task, o.data_file);
  run.data = run.task->build_dataset(o.seed);
  const nn::DynamicsConfig cfg = model_config(o.model, run.data.train_x.cols(), *o.hidden);
  std::mt19937_64 rng(o.seed);
  if (o.dtype == "float") {
    auto f = nn::make_model<float>(cfg, rng);
    nn::load_parameters(run_dir / "params.bin", *f);
    run.model = nn::cast_model<double>(*f);
  } else {
    run.model = nn::make_model<double>(cfg, rng);
    nn::load_parameters(run_dir / "params.bin", *run.model);
  }
  return run;
}

json evaluate_run(const fs::path& run_dir, const std::string& data_file, bool write_files) {
  if (pixel::is_pixel_run(run_dir)) return pixel::evaluate_pixel_run(run_dir, write_files);
  const LoadedRun run = load_run(run_dir, data_file);
  const RunOptions& o = run.options;
  json metrics = evaluate_model(*run.task, run.data, *run.model, o.seed, run_dir, write_files);
  metrics.update({{"task", o.task}, {"model", o.model}, {"seed", o.seed}, {"dtype", o.dtype}});
  return metrics;
}

RunOptions resume_options(const fs::path& run_dir) {
  const TrainState state = read_train_state(checkpoint_dir(run_dir));
  RunOptions o;
  try {
    const json& r = state.run;
    o.task = r.at("task");
    o.model = r.at("model");
    o.seed = json_integer<std::uint64_t>(r.at("seed"), "seed");
    o.dtype = r.at("dtype");
    o.preset = r.value("preset", "paper");  // checkpoints before the presets have none
    o.threads = json_integer<int>(r.at("threads"), "threads");
    o.steps = json_integer<int>(r.at("steps"), "steps");
    o.batch_size = json_integer<int>(r.at("batch_size"), "batch_size");
    o.hidden.emplace();
    for (const json& w : r.at("hidden")) o.hidden->push_back(json_integer<int>(w, "a width"));
    o.learning_rate = r.at("learning_rate");
    o.data_file = r.at("data_file");
  } catch (const std::exception& e) {
    throw Error(fmt::format("the checkpoint in '{}' lacks the run's settings: {}",
                            checkpoint_dir(run_dir).string(), e.what()));
  }
  o.out = run_dir;
  o.resume = true;
  return o;
}

void check_no_unfinished_run(const fs::path& run_dir) {
  if (!fs::exists(checkpoint_dir(run_dir) / "state.json")) return;
  const TrainState state = read_train_state(checkpoint_dir(run_dir));
  HNN_TASKS_CHECK(state.step >= state.total_steps,
                  "'{}' holds an unfinished run (step {} of {}): continue it with `hnn train "
                  "--resume {}`, or choose another --out, or delete '{}'",
                  run_dir.string(), state.step, state.total_steps, run_dir.string(),
                  checkpoint_dir(run_dir).string());
}

}  // namespace hnn::tasks
