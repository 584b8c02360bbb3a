// docs/inputs.md, "Checkpoints", for task 5: the pixel pendulum checkpoints and resumes like
// every task. A run stopped on request (StopSignal) or killed (SIGKILL) and resumed ends with the
// params.bin of the uninterrupted run, bit for bit, and the same loss curve, metrics and
// evaluation files (rollout GIF and strip, latent paths).

#include <gtest/gtest.h>

#include <csignal>
#include <map>

#include "reliability_util.h"
#include "tasks/experiments/pixel_pendulum.h"
#include "tasks/report/run_folder.h"
#include "tasks/run.h"
#include "tasks/train/checkpoint.h"
#include "tasks/train/loop.h"

namespace hnn::reliability {
namespace {

// RUN/checkpoint, where a run keeps its training checkpoints.
fs::path checkpoint_dir(const fs::path& run) { return tasks::RunFolder(run).checkpoint_dir(); }

constexpr int kSteps = 600;

// `hnn train pixel-pendulum` on a tiny configuration: 4 trials of 13 frames (40 pairs, 8 test
// rows), a 16-wide autoencoder and an 8-wide latent HNN; the training settings as options, the
// rest as the task's own settings.
tasks::RunOptions pixel_options(const fs::path& out) {
  tasks::RunOptions o;
  o.task = tasks::kPixelPendulum;
  o.seed = 5;
  o.steps = kSteps;
  o.batch_size = 16;
  o.hidden = std::vector<int>{8};
  o.learning_rate = 3e-3;
  o.task_settings = {{"trials", 4},
                     {"frames_per_trial", 13},
                     {"ae_hidden", 16},
                     {"rollout_frames", 6},
                     {"rollout_trials", 1}};
  o.out = out;
  o.quiet = true;
  o.checkpoint_every = 50;
  return o;
}

long checkpoint_step(const fs::path& run) {
  try {
    return tasks::read_train_state(checkpoint_dir(run)).step;
  } catch (const std::exception&) {
    return -1;
  }
}

// Trains with a stop requested from the start: the loop stops after its first step (step 1 of a
// fresh run, the step after the checkpoint of a resumed one) and checkpoints it.
long stop_after_one_step(tasks::RunOptions o) {
  tasks::StopSignal stop;
  stop.requested = true;
  o.stop = &stop;
  try {
    tasks::run_training(o);
    ADD_FAILURE() << "training was not stopped";
  } catch (const tasks::TrainingInterrupted& e) {
    EXPECT_EQ(e.what(), fmt::format("training stopped at step {} of {}; checkpoint in {}", e.step(),
                                    kSteps, checkpoint_dir(o.out).string()));
    EXPECT_EQ(checkpoint_step(o.out), e.step());
    EXPECT_FALSE(fs::exists(o.out / "metrics.json"));
    EXPECT_FALSE(fs::exists(o.out / "params.bin"));
    return e.step();
  }
  return -1;
}

// Every file of a run folder but its checkpoint, with its bytes.
std::map<std::string, std::string> run_files(const fs::path& run) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(run)) {
    if (entry.is_regular_file()) files[entry.path().filename().string()] = read_text(entry.path());
  }
  return files;
}

// The uninterrupted run every interrupted one must end as, made once.
class PixelResume : public ::testing::Test {
 protected:
  // Once per process, in SetUp (not SetUpTestSuite, whose failures ctest reports as skips).
  void SetUp() override {
    if (whole_) return;
    whole_ = new TempDir("PixelResume.whole");
    ASSERT_NO_THROW(tasks::run_training(pixel_options(*whole_ / "run")));
  }
  static void TearDownTestSuite() {
    delete whole_;
    whole_ = nullptr;
  }
  static void expect_same_as_whole(const fs::path& run) {
    std::map<std::string, std::string> a = run_files(run), b = run_files(*whole_ / "run");
    for (const char* file : {"params.bin", "loss_curve.csv", "metrics.json", "pixel_rollout.csv",
                             "latent_paths.csv", "rollout.gif", "rollout_strip.png"}) {
      EXPECT_TRUE(b.contains(file)) << file;
    }
    EXPECT_EQ(a.at("params.bin"), b.at("params.bin"));
    const nlohmann::json ma = without_timings(nlohmann::json::parse(a.at("metrics.json")));
    const nlohmann::json mb = without_timings(nlohmann::json::parse(b.at("metrics.json")));
    EXPECT_EQ(ma, mb) << ma.dump(1) << "\n" << mb.dump(1);
    a.erase("metrics.json");
    b.erase("metrics.json");
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [name, bytes] : b) EXPECT_TRUE(a.at(name) == bytes) << name << " differs";
  }

  static TempDir* whole_;
  TempDir dir_;
};
TempDir* PixelResume::whole_ = nullptr;

TEST_F(PixelResume, StoppedTwiceAndResumedEqualsUninterruptedBitForBit) {
  const fs::path run = dir_ / "run";
  EXPECT_EQ(stop_after_one_step(pixel_options(run)), 1);
  // The checkpoint keeps the task's own settings: resume_options rebuilds the tiny run.
  tasks::RunOptions resumed = tasks::resume_options(run);
  resumed.quiet = true;
  EXPECT_EQ(resumed.task, tasks::kPixelPendulum);
  EXPECT_EQ(resumed.task_settings, pixel_options(run).task_settings);
  EXPECT_EQ(stop_after_one_step(resumed), 2);  // between checkpoints: step 2 of 600
  const nlohmann::json metrics = tasks::run_training(resumed);
  EXPECT_EQ(metrics["steps"], kSteps);
  expect_same_as_whole(run);
  EXPECT_NO_THROW(tasks::check_no_unfinished_run(run));  // finished: only --force replaces it
  EXPECT_NO_THROW(tasks::check_new_run_folder(run, /*force=*/true));
  EXPECT_THROW(tasks::check_new_run_folder(run, /*force=*/false), tasks::Error);
}

// The program resumes the library's checkpoint (the task's settings come from it), is killed
// mid-run, and resumes from what the kill left to the same end.
TEST_F(PixelResume, KilledAndResumedEqualsUninterruptedBitForBit) {
  const fs::path run = dir_ / "run";
  EXPECT_EQ(stop_after_one_step(pixel_options(run)), 1);
  EXPECT_THROW(tasks::check_no_unfinished_run(run), tasks::Error);  // a fresh run is refused
  {
    Child child({"train", "--resume", run.string(), "--quiet", "--checkpoint-every", "7"},
                dir_.path());
    ASSERT_TRUE(wait_until([&] { return checkpoint_step(run) >= 20; }, 120));
    child.signal(SIGKILL);
    EXPECT_EQ(WTERMSIG(child.wait()), SIGKILL);
  }
  const long killed_at = checkpoint_step(run);
  EXPECT_GE(killed_at, 20);
  EXPECT_LT(killed_at, kSteps) << "the run ended before the kill: make it longer";
  EXPECT_FALSE(fs::exists(run / "metrics.json"));
  const Result resumed = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir_.path());
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_same_as_whole(run);
}

// `hnn rollout` of a pixel run writes RUN/rollout_<integrator>.csv (frames counted by --points)
// and refuses --t-end, writing nothing.
TEST_F(PixelResume, RolloutOfAPixelRunWritesItsCsvAndRefusesTEnd) {
  const fs::path run = dir_ / "run";
  fs::copy(*whole_ / "run", run, fs::copy_options::recursive);
  const Result refused =
      run_hnn({"rollout", run.string(), "--integrator", "rk4", "--t-end", "5"}, dir_.path());
  EXPECT_EQ(refused.code, 1);
  EXPECT_EQ(refused.err,
            "hnn: error: pixel-pendulum rollouts are counted in frames: give --points (frames + "
            "1), not --t-end\n");
  EXPECT_FALSE(fs::exists(run / "rollout_rk4.csv"));
  const Result r = run_hnn(
      {"rollout", run.string(), "--integrator", "rk4", "--points", "4", "--trajectories", "1"},
      dir_.path());
  ASSERT_EQ(r.code, 0) << r.err;
  // 4 points: frames 0..3 of the truth and of the model, for 1 trajectory.
  const std::vector<std::string> csv = lines(read_text(run / "rollout_rk4.csv"));
  ASSERT_EQ(csv.size(), 1u + 2u * 4u);
  EXPECT_EQ(csv[0], "source,traj,t,z_q,z_p,theta,p,energy,learned_h");
  EXPECT_TRUE(csv[1].starts_with("true,0,0,")) << csv[1];
  EXPECT_TRUE(csv[5].starts_with("hnn,0,0,")) << csv[5];
}

}  // namespace
}  // namespace hnn::reliability
