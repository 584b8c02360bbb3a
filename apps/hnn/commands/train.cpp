// `hnn train`: one model on a task, or an interrupted run resumed; Ctrl-C stops after the step
// with a checkpoint.

#include <fmt/format.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <limits>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "tasks/experiments/registry.h"
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
    fmt::print("{}\n", m.dump(2));
    fmt::print(stderr, "hnn train: results in {}\n", o.out.string());
  } catch (const tasks::TrainingInterrupted& e) {
    fmt::print(stderr, "hnn: {}\nhnn: resume with: hnn train --resume {}\n", e.what(),
               o.out.string());
    throw CLI::RuntimeError(130);
  }
}

// `hnn train --resume DIR`: the settings are the checkpoint's; only options that cannot change
// the result may be given again.
tasks::RunOptions resumed_options(const CLI::App& cmd, const std::string& dir, bool quiet) {
  for (const char* name : {"task",          "--model",       "--steps",
                           "--seed",        "--dtype",       "--preset",
                           "--batch",       "--hidden",      "--lr",
                           "--lr-schedule", "--data",        "--settings",
                           "--out",         "--coords",      "--momenta",
                           "--velocities",  "--derivatives", "--time",
                           "--trajectory",  "--split",       "--test-fraction",
                           "--hamiltonian", "--loss",        "--horizon",
                           "--integrator",  "--dt"}) {
    if (cmd.get_option(name)->count() > 0) {
      throw std::invalid_argument(fmt::format(
          "{} cannot be combined with --resume: a resumed run keeps its own settings", name));
    }
  }
  tasks::RunOptions o = tasks::resume_options(dir);
  o.quiet = quiet;
  if (cmd.get_option("--threads")->count() > 0) o.threads = cmd.get_option("--threads")->as<int>();
  if (cmd.get_option("--checkpoint-every")->count() > 0) {
    o.checkpoint_every = cmd.get_option("--checkpoint-every")->as<long>();
  }
  return o;
}

// --settings: a JSON object, or one line saying why not.
nlohmann::json task_settings(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) {
    throw std::invalid_argument(
        fmt::format("--settings must be a JSON object like '{{\"trials\": 20}}', got '{}'", text));
  }
  return j;
}

}  // namespace

void add_train_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("train", "Train and evaluate one model on a task");
  auto options = std::make_shared<tasks::RunOptions>();
  auto model = std::make_shared<std::string>("hnn"),
       dtype = std::make_shared<std::string>("double");
  auto preset = std::make_shared<std::string>("paper");
  auto steps = std::make_shared<int>(0), batch = std::make_shared<int>(-1);
  auto lr = std::make_shared<double>(0);
  auto hidden = std::make_shared<std::vector<int>>();
  auto resume = std::make_shared<std::string>();
  auto checkpoint_every = std::make_shared<long>(0);
  cmd->add_option("task", options->task, "Task: " + task_list() + " (required unless --resume)");
  cmd->add_option("--model", *model,
                  "hnn, baseline, dhnn (the dissipative HNN: H and a dissipation potential D) or "
                  "lnn (the Lagrangian NN: L(q, dq/dt))")
      ->check(CLI::IsMember(tasks::model_names()))
      ->capture_default_str();
  cmd->add_option("--steps", *steps, "Training steps (default: the paper's)")
      ->check(positive_integer());
  cmd->add_option("--seed", options->seed, "Seed of the data, initialisation and batches")
      ->check(seed_value())
      ->capture_default_str();
  cmd->add_option("--dtype", *dtype, "float or double")
      ->check(CLI::IsMember(tasks::dtype_names()))
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Threads for matrix products")
      ->check(integer_in(1, 256))
      ->capture_default_str();
  cmd->add_option("--preset", *preset,
                  "Model widths: paper (the paper's 200-200) or lean (the smallest within the "
                  "noise of paper's accuracy); --hidden overrides either")
      ->check(CLI::IsMember(tasks::preset_names()))
      ->capture_default_str();
  cmd->add_option("--batch", *batch, "Minibatch size (0: full batch; default: the paper's)")
      ->check(integer_in(0, std::numeric_limits<int>::max()));
  cmd->add_option("--hidden", *hidden, "Hidden widths, e.g. --hidden 200 200")
      ->check(integer_in(1, tasks::kMaxWidth));
  cmd->add_option("--lr", *lr, "Adam learning rate (default 1e-3)")->check(positive_real());
  auto lr_schedule = std::make_shared<std::string>();
  cmd->add_option("--lr-schedule", *lr_schedule,
                  "constant (the default) or cosine: decay from --lr towards 0 at the last step")
      ->check(CLI::IsMember({"constant", "cosine"}));
  cmd->add_option("--data", options->data_file,
                  "The data task's file, or real-pendulum's measured data in its format");
  cmd->add_option("--out", options->out, "Run folder (default runs/TASK/MODEL)");
  cmd->add_flag("--quiet", options->quiet, "No progress output");
  auto settings = std::make_shared<std::string>();
  cmd->add_option("--settings", *settings,
                  "The task's own settings as a JSON object, e.g. pixel-pendulum's "
                  "'{\"trials\": 20, \"ae_hidden\": 64}' (see its metrics.json's \"pixel\")");
  cmd->add_option("--checkpoint-every", *checkpoint_every,
                  "Steps between checkpoints in OUT/checkpoint (default: a tenth of the steps)")
      ->check(positive_integer());
  cmd->add_option("--resume", *resume,
                  "Continue the interrupted run in this folder from its last checkpoint")
      ->check(CLI::ExistingDirectory);
  const auto data_options = add_data_options(*cmd);
  cmd->callback([=] {
    if (!resume->empty())
      return train_until_done_or_stopped(resumed_options(*cmd, *resume, options->quiet));
    tasks::RunOptions o = *options;
    if (o.task.empty()) throw std::invalid_argument("train needs a TASK (or --resume DIR)");
    o.model = tasks::parse_model(*model);
    o.dtype = tasks::parse_dtype(*dtype);
    o.preset = tasks::parse_preset(*preset);
    if (!settings->empty()) o.task_settings = task_settings(*settings);
    data_options(o.task_settings, o.task);
    if (*steps > 0) o.steps = *steps;
    if (*batch >= 0) o.batch_size = *batch;
    if (*lr > 0) o.learning_rate = *lr;
    if (!lr_schedule->empty()) o.lr_schedule = tasks::parse_lr_schedule(*lr_schedule);
    if (!hidden->empty()) o.hidden = *hidden;
    if (*checkpoint_every > 0) o.checkpoint_every = *checkpoint_every;
    if (o.out.empty()) o.out = std::filesystem::path("runs") / o.task / *model;
    tasks::check_no_unfinished_run(o.out);
    train_until_done_or_stopped(o);
  });
}

}  // namespace hnn::app
