// docs/inputs.md, "Checkpoints" and faults: a run stopped at any step (on request, by SIGINT, by
// SIGKILL) and resumed ends with the parameters of the uninterrupted run, bit for bit; a kill
// leaves only complete files; divergence keeps the last good checkpoint.

#include <gtest/gtest.h>

#include <csignal>

#include "nn/hnn.h"
#include "nn/parameter_file.h"
#include "reliability_util.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_model_run.h"
#include "tasks/field/field_task.h"
#include "tasks/report/run_folder.h"
#include "tasks/run.h"
#include "tasks/train/checkpoint.h"
#include "tasks/train/loop.h"

namespace hnn::reliability {
namespace {

// RUN/checkpoint, where a run keeps its training checkpoints.
fs::path checkpoint_dir(const fs::path& run) { return tasks::RunFolder(run).checkpoint_dir(); }

// ---- the library: train_model stopped and resumed -------------------------------------------

template <typename T>
struct Trained {
  std::vector<nn::Matrix<T>> params;
  std::vector<tasks::CurvePoint> curve;
};

// Trains a small spring HNN for `steps`; stops after `stop_at` (0: never) when `dir` is given;
// resumes from `dir` when `resume` is set.
template <typename T>
Trained<T> train_spring(int batch, long stop_at, const fs::path& dir, bool resume,
                        tasks::LrSchedule schedule = tasks::LrSchedule::kConstant) {
  const auto task = tasks::make_field_task("spring");
  const tasks::Dataset data = task->build_dataset(4);
  tasks::TrainConfig config = task->train_config();
  config.steps = 40;
  config.batch_size = batch;
  config.learning_rate = 1e-2;
  config.lr_schedule = schedule;
  nn::DynamicsConfig model_config;
  model_config.hidden = {8};
  std::mt19937_64 init(4);
  const auto model = nn::make_model<T>(model_config, init);
  tasks::StopSignal stop;
  tasks::LoopOptions loop;
  loop.quiet = true;
  loop.on_record = [&](long step) { stop.requested = step == stop_at; };
  loop.checkpoint_dir = dir;
  loop.checkpoint_every = 10;
  loop.resume = resume;
  loop.stop = &stop;
  Trained<T> out;
  try {
    out.curve = tasks::train_model<T>(*model, data, config, 4, loop).curve;
  } catch (const tasks::TrainingInterrupted& e) {
    EXPECT_EQ(e.step(), stop_at);
    EXPECT_EQ(e.what(), fmt::format("training stopped at step {} of 40; checkpoint in {}", stop_at,
                                    dir.string()));
  }
  for (const auto& p : model->parameters()) out.params.push_back(p.value());
  return out;
}

template <typename T>
void expect_resume_matches(int batch, long stop_at,
                           tasks::LrSchedule schedule = tasks::LrSchedule::kConstant) {
  const TempDir dir;
  const Trained<T> whole = train_spring<T>(batch, 0, "", false, schedule);
  train_spring<T>(batch, stop_at, dir / "checkpoint", false, schedule);
  EXPECT_EQ(tasks::read_train_state(dir / "checkpoint").step, stop_at);
  const Trained<T> resumed = train_spring<T>(batch, 0, dir / "checkpoint", true, schedule);
  ASSERT_EQ(whole.params.size(), resumed.params.size());
  for (std::size_t i = 0; i < whole.params.size(); ++i) {
    EXPECT_EQ(whole.params[i], resumed.params[i]) << "parameter " << i << ", batch " << batch;
  }
  ASSERT_EQ(whole.curve.size(), resumed.curve.size());
  for (std::size_t i = 0; i < whole.curve.size(); ++i) {
    EXPECT_EQ(whole.curve[i].train_loss, resumed.curve[i].train_loss) << i;
    EXPECT_EQ(whole.curve[i].test_loss, resumed.curve[i].test_loss) << i;
  }
}

TEST(Resume, StoppedAndResumedEqualsUninterruptedBitForBit) {
  expect_resume_matches<double>(/*batch=*/0, /*stop_at=*/17);   // between checkpoints
  expect_resume_matches<double>(/*batch=*/25, /*stop_at=*/20);  // at one; minibatch generator
  expect_resume_matches<double>(/*batch=*/25, /*stop_at=*/1);
  expect_resume_matches<float>(/*batch=*/25, /*stop_at=*/33);
}

// The cosine schedule is a function of the step alone, so a resumed run follows it too; and it
// is honoured: the run ends elsewhere than at a constant rate.
TEST(Resume, ACosineScheduleResumesBitForBitAndChangesTheRun) {
  expect_resume_matches<double>(/*batch=*/25, /*stop_at=*/20, tasks::LrSchedule::kCosine);
  const auto constant = train_spring<double>(25, 0, "", false);
  const auto cosine = train_spring<double>(25, 0, "", false, tasks::LrSchedule::kCosine);
  EXPECT_NE(constant.params.front(), cosine.params.front());
}

TEST(Resume, RefusesACorruptCheckpointAndChangesNothing) {
  const TempDir dir;
  train_spring<double>(25, 17, dir / "checkpoint", false);
  const tasks::TrainState state = tasks::read_train_state(dir / "checkpoint");
  const fs::path bin = dir / "checkpoint" / state.params_file;
  const std::string bytes = read_text(bin);
  write_text(bin, bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(train_spring<double>(25, 0, dir / "checkpoint", true), nn::ParameterFileError);
  write_text(bin, bytes);
  const std::string json = read_text(dir / "checkpoint" / "state.json");
  write_text(dir / "checkpoint" / "state.json", json.substr(0, json.size() / 2));
  EXPECT_THROW(tasks::read_train_state(dir / "checkpoint"), tasks::Error);
}

// ---- the program: SIGINT, SIGKILL, --resume ---------------------------------------------------

// Long enough (a few seconds) that signals land during training.
const std::vector<std::string> kLongRun = {"train",   "spring", "--hidden", "16", "--batch", "25",
                                           "--steps", "30000",  "--seed",   "3",  "--quiet"};

std::vector<std::string> long_run(const fs::path& out, const std::string& every) {
  std::vector<std::string> args = kLongRun;
  args.insert(args.end(), {"--checkpoint-every", every, "--out", out.string()});
  return args;
}

long checkpoint_step(const fs::path& run) {
  try {
    return tasks::read_train_state(checkpoint_dir(run)).step;
  } catch (const std::exception&) {
    return -1;
  }
}

// The run both interrupted runs must end as, made once.
class ResumeCli : public ::testing::Test {
 protected:
  // Once per process, in SetUp (not SetUpTestSuite, whose failures ctest reports as skips).
  void SetUp() override {
    if (whole_) return;
    whole_ = new TempDir("ResumeCli.whole");
    const Result r = run_hnn(long_run(*whole_ / "run", "1000"), whole_->path());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete whole_;
    whole_ = nullptr;
  }
  static void expect_same_as_whole(const fs::path& run) {
    const fs::path whole = *whole_ / "run";
    EXPECT_EQ(read_text(run / "params.bin"), read_text(whole / "params.bin"));
    EXPECT_EQ(read_text(run / "loss_curve.csv"), read_text(whole / "loss_curve.csv"));
    EXPECT_EQ(read_text(run / "rollout.csv"), read_text(whole / "rollout.csv"));
    nlohmann::json a = without_timings(read_json(run / "metrics.json"));
    nlohmann::json b = without_timings(read_json(whole / "metrics.json"));
    EXPECT_EQ(a, b) << a.dump(1) << "\n" << b.dump(1);
  }

  static TempDir* whole_;
  TempDir dir_;
};
TempDir* ResumeCli::whole_ = nullptr;

TEST_F(ResumeCli, SigintStopsAfterTheStepCheckpointsAndSaysHowToResume) {
  const fs::path run = dir_ / "run";
  Child child(long_run(run, "1000"), dir_.path());
  ASSERT_TRUE(wait_until([&] { return checkpoint_step(run) >= 1000; }, 60));
  child.signal(SIGINT);
  const int status = child.wait();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const long step = checkpoint_step(run);
  EXPECT_GT(step, 1000);
  EXPECT_LT(step, 30000);
  EXPECT_EQ(child.err(),
            fmt::format("\nhnn: stopping after this step (press Ctrl-C again to quit now)\n"
                        "hnn: training stopped at step {} of 30000; checkpoint in {}\n"
                        "hnn: resume with: hnn train --resume {}\n",
                        step, checkpoint_dir(run).string(), run.string()));
  EXPECT_FALSE(fs::exists(run / "metrics.json"));
  // A fresh run into the folder would lose the checkpoint: refused.
  const Result fresh = run_hnn(long_run(run, "1000"), dir_.path());
  EXPECT_EQ(fresh.code, 1);
  EXPECT_EQ(fresh.err, fmt::format("hnn: error: '{0}' holds an unfinished run (step {1} of "
                                   "30000): continue it with `hnn train --resume {0}`, or replace "
                                   "it with --force, or choose another --out\n",
                                   run.string(), step));
  const Result resumed = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir_.path());
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_same_as_whole(run);
}

// Every file in the run folder is complete: state.json parses and the checkpoint it names loads
// into a model and an optimiser. Other files can only be the temporaries of an unfinished atomic
// write, or a complete .bin of a checkpoint killed before its commit (or after, before the
// older one's removal): see Note [Checkpoint commit].
void expect_complete_files(const fs::path& run) {
  const tasks::TrainState state = tasks::read_train_state(checkpoint_dir(run));
  nn::DynamicsConfig config;
  config.hidden = {16};
  std::mt19937_64 rng(0);
  const auto model = nn::make_model<double>(config, rng);
  nn::Adam<double> adam(model->parameters());
  tasks::load_train_checkpoint<double>(checkpoint_dir(run), state, *model, adam);
  EXPECT_EQ(adam.step_count(), state.step);
  for (const auto& entry : fs::recursive_directory_iterator(run)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() || name == "state.json" || name == state.params_file) continue;
    if (name.find(".tmp") != std::string::npos) continue;
    EXPECT_TRUE(name.starts_with("step-")) << "unexpected file " << entry.path();
    EXPECT_NO_THROW(nn::read_parameter_file_info(entry.path())) << entry.path();
  }
}

TEST_F(ResumeCli, SigkillLeavesCompleteFilesAndResumesToTheSameEnd) {
  const fs::path run = dir_ / "run";
  {
    Child child(long_run(run, "100"), dir_.path());  // frequent checkpoints: kills land in writes
    ASSERT_TRUE(wait_until([&] { return checkpoint_step(run) >= 2000; }, 60));
    child.signal(SIGKILL);
    EXPECT_EQ(WTERMSIG(child.wait()), SIGKILL);
  }
  expect_complete_files(run);
  {
    Child child({"train", "--resume", run.string(), "--quiet"}, dir_.path());
    const long first = checkpoint_step(run);
    ASSERT_TRUE(wait_until([&] { return checkpoint_step(run) > first + 2000; }, 60));
    child.signal(SIGKILL);
    EXPECT_EQ(WTERMSIG(child.wait()), SIGKILL);
  }
  expect_complete_files(run);
  EXPECT_FALSE(fs::exists(run / "metrics.json"));
  const Result resumed = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir_.path());
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_same_as_whole(run);
  // Resuming a finished run only evaluates it again: the same files.
  const Result again = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir_.path());
  ASSERT_EQ(again.code, 0) << again.err;
  expect_same_as_whole(run);
}

TEST(ResumeOptions, ConflictsAndMissingCheckpointsGetOneLine) {
  const TempDir dir;
  const Result none = run_hnn({"train", "--resume", dir.path().string()}, dir.path());
  EXPECT_EQ(none.code, 1);
  EXPECT_EQ(none.err, fmt::format("hnn: error: no checkpoint in '{0}/checkpoint' (cannot read "
                                  "'{0}/checkpoint/state.json')\n",
                                  dir.path().string()));
  // Every setting of the run is refused next to --resume (the checkpoint's are used); --steps
  // continues a finished run and --data names its moved data file (continue_run_test.cpp,
  // run_folders_test.cpp).
  const std::vector<std::vector<std::string>> settings = {
      {"--model", "baseline"},     {"--seed", "2"}, {"--dtype", "float"},   {"--batch", "5"},
      {"--hidden", "4"},           {"--lr", "0.1"}, {"--out", "elsewhere"}, {"--force"},
      {"--lr-schedule", "cosine"}, {"spring"}};
  for (const std::vector<std::string>& setting : settings) {
    std::vector<std::string> args = {"train", "--resume", dir.path().string()};
    args.insert(args.end(), setting.begin(), setting.end());
    const Result both = run_hnn(args, dir.path());
    const std::string name = setting[0].starts_with("--") ? setting[0] : "task";
    EXPECT_EQ(both.code, 1) << name;
    EXPECT_EQ(both.err, "hnn: error: " + name +
                            " cannot be combined with --resume: a resumed run keeps its own "
                            "settings\n");
  }
}

// SIGTERM (a scheduler's stop) is handled as Ctrl-C: the step finishes, a complete checkpoint
// is written and the way to resume is printed.
TEST_F(ResumeCli, SigtermStopsLikeSigint) {
  const fs::path run = dir_ / "run";
  Child child(long_run(run, "1000"), dir_.path());
  ASSERT_TRUE(wait_until([&] { return checkpoint_step(run) >= 1000; }, 60));
  child.signal(SIGTERM);
  const int status = child.wait();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const long step = checkpoint_step(run);
  EXPECT_GT(step, 1000);
  EXPECT_TRUE(child.err().ends_with(
      fmt::format("hnn: training stopped at step {} of 30000; checkpoint in {}\n"
                  "hnn: resume with: hnn train --resume {}\n",
                  step, checkpoint_dir(run).string(), run.string())))
      << child.err();
  expect_complete_files(run);
}

// A loss that overflows (the baseline) and a gradient that does (the HNN, whose loss stays
// finite on saturated units): either stops training at that step with the reason, before the
// update, and keeps the checkpoint of the step before, whose parameters are finite.
TEST(Divergence, StopsAtTheStepAndKeepsTheLastGoodCheckpoint) {
  const TempDir dir;
  for (const auto& [model, reason] :
       {std::pair<std::string, std::string>{"baseline", "the loss is inf"},
        {"hnn", "but its gradient is not finite"}}) {
    const fs::path run = dir / model;
    const Result r =
        run_hnn({"train", "spring", "--model", model, "--hidden", "8", "--steps", "10", "--lr",
                 "1e200", "--checkpoint-every", "1", "--quiet", "--out", run.string()},
                dir.path());
    EXPECT_EQ(r.code, 1);
    // The HNN's finite loss before `reason` depends on the weights: only its ends are checked.
    EXPECT_TRUE(r.err.starts_with("hnn: error: training diverged at step 2: ")) << r.err;
    EXPECT_TRUE(r.err.ends_with(fmt::format("{}; the last good checkpoint (step 1) is kept in {}\n",
                                            reason, checkpoint_dir(run).string())))
        << r.err;
    EXPECT_FALSE(fs::exists(run / "metrics.json"));
    EXPECT_FALSE(fs::exists(run / "params.bin"));
    const tasks::TrainState state = tasks::read_train_state(checkpoint_dir(run));
    EXPECT_EQ(state.step, 1);
    ASSERT_EQ(state.curve.size(), 1u);
    EXPECT_TRUE(std::isfinite(state.curve[0].train_loss));
  }
}

}  // namespace
}  // namespace hnn::reliability
