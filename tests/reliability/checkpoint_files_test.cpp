// docs/inputs.md, "Training checkpoints" and "Faults while running": `hnn train --resume` refuses
// every kind of bad checkpoint with one line and changes no file; leftovers of a kill are ignored
// and cleared; a run that diverges between checkpoints keeps the earlier one intact.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "autodiff/ops.h"
#include "nn/hnn.h"
#include "nn/parameter_file.h"
#include "reliability_util.h"
#include "tasks/data/file_digest.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_model_run.h"
#include "tasks/field/field_task.h"
#include "tasks/train/checkpoint.h"
#include "tasks/train/field_objective.h"
#include "tasks/train/loop.h"

namespace hnn::reliability {
namespace {

// Every file under `dir` with its bytes.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) {
      files[fs::relative(entry.path(), dir).string()] = read_text(entry.path());
    }
  }
  return files;
}

void edit_state(const fs::path& run, const std::function<void(nlohmann::json&)>& edit) {
  const fs::path file = run / "checkpoint" / "state.json";
  nlohmann::json state = read_json(file);
  edit(state);
  write_text(file, state.dump());
}

class CheckpointFiles : public ::testing::Test {
 protected:
  // A finished run keeps its last checkpoint; each case edits a copy and resumes it.
  // Once per process, in SetUp (not SetUpTestSuite, whose failures ctest reports as skips).
  void SetUp() override {
    if (good_) return;
    good_ = new TempDir("CheckpointFiles.good");
    const Result r =
        run_hnn({"train", "spring", "--steps", "20", "--hidden", "8", "--batch", "25",
                 "--checkpoint-every", "5", "--quiet", "--out", (*good_ / "run").string()},
                good_->path());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete good_;
    good_ = nullptr;
  }

  static TempDir* good_;
  TempDir dir_;
};
TempDir* CheckpointFiles::good_ = nullptr;

TEST_F(CheckpointFiles, EveryBadCheckpointIsOneLineAndChangesNoFile) {
  struct Case {
    std::string name;
    std::function<void(const fs::path&)> edit;
    std::string message;  // after "hnn: error: "; RUN stands for the run folder
  };
  const std::string unreadable = "'RUN/checkpoint/state.json' is not a readable checkpoint: ";
  const auto set = [&](const std::string& key, const nlohmann::json& value) {
    return [key, value](const fs::path& run) {
      edit_state(run, [&](nlohmann::json& s) { s[key] = value; });
    };
  };
  const std::vector<Case> cases = {
      {"cut",
       [](const fs::path& run) {
         const fs::path f = run / "checkpoint" / "state.json";
         write_text(f, read_text(f).substr(0, 40));
       },
       unreadable +
           "[json.exception.parse_error.101] parse error at line 1, column 41: syntax error while "
           "parsing array - unexpected end of input; expected ']'"},
      {"foreign", [](const fs::path& run) { write_text(run / "checkpoint" / "state.json", "[]"); },
       unreadable + "it is not an hnn training checkpoint"},
      {"other-version", set("version", 2),
       unreadable + "format version 2, but this build reads version 1"},
      {"text-step", set("step", "5"),
       unreadable + "step is \"5\", not an integer from -9223372036854775808 to "
                    "9223372036854775807"},
      {"fractional-step", set("step", 2.5),
       unreadable + "step is 2.5, not an integer from -9223372036854775808 to "
                    "9223372036854775807"},
      {"huge-hash", set("data_hash", -1),
       unreadable + "data_hash is -1, not an integer from 0 to 18446744073709551615"},
      {"step-past-the-end", set("step", 21), unreadable + "step 21 of 20 is out of range"},
      {"missing-key",
       [](const fs::path& run) { edit_state(run, [](nlohmann::json& s) { s.erase("curve"); }); },
       unreadable + "[json.exception.out_of_range.403] key 'curve' not found"},
      {"params-outside", set("params_file", "../params.bin"),
       unreadable + "params_file '../params.bin' is not a checkpoint of this folder"},
      {"params-absolute", set("params_file", "/etc/passwd"),
       unreadable + "params_file '/etc/passwd' is not a checkpoint of this folder"},
      {"settings-missing",
       [](const fs::path& run) {
         edit_state(run, [](nlohmann::json& s) { s["run"].erase("seed"); });
       },
       "the checkpoint in 'RUN/checkpoint' does not hold a run's settings: "
       "[json.exception.out_of_range.403] key 'seed' not found"},
      {"other-step-count",
       [](const fs::path& run) {
         edit_state(run, [](nlohmann::json& s) { s["run"]["steps"] = 30; });
       },
       "the checkpoint in 'RUN/checkpoint' is of a run of 20 steps, not 30"},
      {"other-data",
       [](const fs::path& run) {
         edit_state(run, [](nlohmann::json& s) { s["run"]["seed"] = 1; });
       },
       "the training data differ from those of the checkpoint in 'RUN/checkpoint'"},
      {"cut-bin",
       [](const fs::path& run) {
         const fs::path bin = run / "checkpoint" / "step-000000020.bin";
         write_text(bin, read_text(bin).substr(0, 100));
       },
       "parameter file 'RUN/checkpoint/step-000000020.bin': truncated: parameter "
       "'model/mlp.layers.0.weight' is 2x8 but only 1 bytes remain at offset 99"},
      {"missing-bin",
       [](const fs::path& run) { fs::remove(run / "checkpoint" / "step-000000020.bin"); },
       "parameter file 'RUN/checkpoint/step-000000020.bin': cannot open for reading: No such file "
       "or directory"},
  };
  for (const Case& c : cases) {
    const fs::path run = dir_ / c.name;
    fs::copy(*good_ / "run", run, fs::copy_options::recursive);
    c.edit(run);
    const auto before = snapshot(run);
    std::string message = c.message;
    for (std::size_t at; (at = message.find("RUN")) != std::string::npos;) {
      message.replace(at, 3, run.string());
    }
    const Result r = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir_.path());
    EXPECT_EQ(r.code, 1) << c.name;
    EXPECT_EQ(r.err, "hnn: error: " + message + "\n") << c.name;
    EXPECT_TRUE(snapshot(run) == before) << c.name << ": a file changed";
  }
}

// The data file of a measured-data run changed after its checkpoint: refused, nothing written.
TEST(CheckpointData, ChangedDataFileIsRefused) {
  const TempDir dir;
  const fs::path data = dir / "pendulum.txt", run = dir / "run";
  write_text(data, read_text(shipped_pendulum_data()));
  const Result trained = run_hnn({"train", "real-pendulum", "--data", data.string(), "--steps", "4",
                                  "--hidden", "8", "--quiet", "--out", run.string()},
                                 dir.path());
  ASSERT_EQ(trained.code, 0) << trained.err;
  // The first row's angle, changed in its last digit (the first rows are training data).
  std::string text = read_text(data);
  const std::size_t at = text.find("1.1383885512243586");
  ASSERT_NE(at, std::string::npos);
  text[at + 17] = '7';
  write_text(data, text);
  auto before = snapshot(run);
  const nlohmann::json state = read_json(run / "checkpoint" / "state.json");
  const std::string recorded = state["run"]["data_sha256"];
  const Result r = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, fmt::format("hnn: error: '{}' is not the data file of run '{}' (its SHA-256 is "
                               "{}..., the run's {}...): give the run's own file with --data "
                               "FILE\n",
                               data.string(), run.string(), tasks::file_sha256(data).substr(0, 12),
                               recorded.substr(0, 12)));
  EXPECT_TRUE(snapshot(run) == before);
  // A checkpoint from before the checksum: the fingerprint of the training data refuses it.
  nlohmann::json old = state;
  old["run"].erase("data_sha256");
  write_text(run / "checkpoint" / "state.json", old.dump());
  before = snapshot(run);
  const Result unsummed = run_hnn({"train", "--resume", run.string(), "--quiet"}, dir.path());
  EXPECT_EQ(unsummed.code, 1);
  EXPECT_EQ(unsummed.err, fmt::format("hnn: error: the training data differ from those of the "
                                      "checkpoint in '{}'\n",
                                      (run / "checkpoint").string()));
  EXPECT_TRUE(snapshot(run) == before);
}

// ---- the library: leftovers of a kill, divergence between checkpoints ------------------------

struct SpringRun {
  std::unique_ptr<nn::DynamicsModel<double>> model;
  tasks::Dataset data;
  tasks::TrainConfig config;
};

SpringRun spring_run() {
  SpringRun run;
  const auto task = tasks::make_field_task("spring");
  run.data = task->build_dataset(4);
  run.config = task->train_config();
  run.config.steps = 30;
  run.config.batch_size = 25;
  run.config.learning_rate = 1e-2;
  run.config.record_every = 1;
  nn::DynamicsConfig model_config;
  model_config.hidden = {8};
  std::mt19937_64 init(4);
  run.model = nn::make_model<double>(model_config, init);
  return run;
}

tasks::LoopOptions checkpoint_loop(const fs::path& dir, bool resume) {
  tasks::LoopOptions loop;
  loop.quiet = true;
  loop.checkpoint_dir = dir;
  loop.checkpoint_every = 10;
  loop.resume = resume;
  return loop;
}

// A kill between writing step-N.bin and committing state.json, or during a write, leaves an
// uncommitted .bin and temporaries: resume ignores them and the next checkpoint removes them.
TEST(CheckpointLeftovers, AreIgnoredByResumeAndRemovedByTheNextCheckpoint) {
  const TempDir dir;
  const fs::path ckpt = dir / "checkpoint";
  SpringRun whole = spring_run();
  tasks::train_model<double>(*whole.model, whole.data, whole.config, 4, {});

  SpringRun first = spring_run();
  tasks::StopSignal stop;
  tasks::LoopOptions loop = checkpoint_loop(ckpt, false);
  loop.stop = &stop;
  loop.on_record = [&](long step) { stop.requested = step == 12; };
  EXPECT_THROW(tasks::train_model<double>(*first.model, first.data, first.config, 4, loop),
               tasks::TrainingInterrupted);
  ASSERT_EQ(tasks::read_train_state(ckpt).step, 12);
  // A complete but uncommitted later checkpoint (another run's bytes), and torn temporaries.
  SpringRun other = spring_run();
  other.model->parameters()[0].mutable_value().setConstant(7);
  nn::save_parameters(ckpt / "step-000000020.bin", *other.model);
  write_text(ckpt / "state.json.tmp.123", "{\"step\": 2");
  write_text(ckpt / "step-000000030.bin.tmp.123", "HNN");

  SpringRun resumed = spring_run();
  tasks::train_model<double>(*resumed.model, resumed.data, resumed.config, 4,
                             checkpoint_loop(ckpt, true));
  const auto a = whole.model->parameters(), b = resumed.model->parameters();
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].value(), b[i].value()) << i;
  std::vector<std::string> left;
  for (const auto& entry : fs::directory_iterator(ckpt)) {
    left.push_back(entry.path().filename().string());
  }
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"state.json", "step-000000030.bin"}));
}

// Parameters poisoned after step 13 make the loss NaN at step 14: training stops there, and the
// checkpoint of step 10 is kept, complete and finite, as an uninterrupted run wrote it.
TEST(Divergence, BetweenCheckpointsKeepsTheEarlierOneIntact) {
  const TempDir dir;
  SpringRun reference = spring_run();
  tasks::LoopOptions at_ten = checkpoint_loop(dir / "reference", false);
  tasks::StopSignal stop;
  at_ten.stop = &stop;
  at_ten.on_record = [&](long step) { stop.requested = step == 10; };
  EXPECT_THROW(
      tasks::train_model<double>(*reference.model, reference.data, reference.config, 4, at_ten),
      tasks::TrainingInterrupted);

  const fs::path ckpt = dir / "checkpoint";
  SpringRun run = spring_run();
  tasks::LoopOptions loop = checkpoint_loop(ckpt, false);
  loop.on_record = [&](long step) {
    if (step == 13) {
      run.model->parameters()[0].mutable_value()(0, 0) = std::numeric_limits<double>::quiet_NaN();
    }
  };
  try {
    tasks::train_model<double>(*run.model, run.data, run.config, 4, loop);
    ADD_FAILURE() << "trained through NaN parameters";
  } catch (const tasks::TrainingDiverged& e) {
    EXPECT_EQ(e.step(), 14);
    // The NaN's sign bit depends on the ops it went through (fmt prints "-nan" for it).
    const std::string tail =
        fmt::format("nan; the last good checkpoint (step 10) is kept in {}", ckpt.string());
    const std::string what = e.what();
    EXPECT_TRUE(what == "training diverged at step 14: the loss is " + tail ||
                what == "training diverged at step 14: the loss is -" + tail)
        << what;
  }
  const tasks::TrainState state = tasks::read_train_state(ckpt);
  EXPECT_EQ(state.step, 10);
  EXPECT_EQ(read_text(ckpt / state.params_file),
            read_text(dir / "reference" / tasks::read_train_state(dir / "reference").params_file));
  SpringRun loaded = spring_run();
  nn::Adam<double> adam(loaded.model->parameters());
  tasks::load_train_checkpoint<double>(ckpt, state, *loaded.model, adam);
  for (const auto& p : loaded.model->parameters()) EXPECT_TRUE(p.value().allFinite());
}

// The spring's field objective, whose loss gains sqrt(0 |w|^2) from step `from` on: the term's
// value 0 leaves the loss finite, its gradient 0 / (2 sqrt 0) is NaN.
class NanGradientFrom : public tasks::Objective<double> {
 public:
  NanGradientFrom(nn::DynamicsModel<double>& model, const tasks::Dataset& data,
                  const tasks::TrainConfig& config, long from)
      : inner_(model, data, config.batch_size, tasks::adam_options(config), 4), from_(from) {}
  nn::Module<double>& model() override { return inner_.model(); }
  std::vector<nn::AdamGroup<double>> parameter_groups() const override {
    return inner_.parameter_groups();
  }
  tasks::RowSampler& sampler() override { return inner_.sampler(); }
  ad::Var<double> batch_loss() override {
    const ad::Var<double> loss = inner_.batch_loss();
    if (++steps_ < from_) return loss;
    return loss + ad::sqrt(ad::sum(ad::square(inner_.model().parameters()[0])) * 0.0);
  }
  tasks::CurvePoint curve_point(long step, double batch_loss) const override {
    return inner_.curve_point(step, batch_loss);
  }
  std::uint64_t data_fingerprint() const override { return inner_.data_fingerprint(); }

 private:
  tasks::FieldObjective<double> inner_;
  long from_, steps_ = 0;
};

// A finite loss whose gradient is not finite stops the run at that step, saying so, before the
// update: the parameters and the last checkpoint stay finite.
TEST(Divergence, ANonFiniteGradientOfAFiniteLossStopsBeforeTheUpdate) {
  const TempDir dir;
  const fs::path ckpt = dir / "checkpoint";
  SpringRun run = spring_run();
  NanGradientFrom objective(*run.model, run.data, run.config, 14);
  try {
    tasks::train(objective, tasks::with_train_config(checkpoint_loop(ckpt, false), run.config));
    ADD_FAILURE() << "trained on a NaN gradient";
  } catch (const tasks::TrainingDiverged& e) {
    EXPECT_EQ(e.step(), 14);
    const std::string what = e.what();
    EXPECT_TRUE(what.starts_with("training diverged at step 14: the loss is ")) << what;
    EXPECT_TRUE(
        what.ends_with(fmt::format(" but its gradient is not finite; the last good "
                                   "checkpoint (step 10) is kept in {}",
                                   ckpt.string())))
        << what;
  }
  for (const auto& p : run.model->parameters()) EXPECT_TRUE(p.value().allFinite());
  EXPECT_EQ(tasks::read_train_state(ckpt).step, 10);
}

}  // namespace
}  // namespace hnn::reliability
