// The training presets (issue 7, chart 4): "paper" keeps each task's published widths, "lean"
// swaps in the smaller widths the model-size sweep chose (docs/speed_accuracy.md), --hidden
// overrides either, and anything else is refused before work starts.

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>

#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/run.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

using testing::read_json;
using testing::TempDir;

// Weights and biases of dim -> hidden... -> 1 (the HNN's H).
long hnn_parameters(int dim, const std::vector<int>& hidden) {
  long n = 0, in = dim;
  for (int w : hidden) {
    n += (in + 1) * w;
    in = w;
  }
  return n + in + 1;
}

// The training settings a run of `task` gets under a preset.
TrainConfig train_config(const Task& task, Preset preset) {
  return resolve(task, {.task = task.name(), .preset = preset}).train;
}

TEST(Presets, AreNamedPaperAndLean) {
  EXPECT_EQ(preset_names(), (std::vector<std::string>{"paper", "lean"}));
}

TEST(Presets, PaperIsTheTasksOwnConfiguration) {
  for (const std::string& name : paper_task_names()) {
    const auto task = make_task(name);
    const TrainConfig own = task->train_config(), paper = train_config(*task, Preset::kPaper);
    EXPECT_EQ(paper.hidden, own.hidden) << name;
    EXPECT_EQ(paper.hidden, (std::vector<int>{200, 200})) << name;
    EXPECT_EQ(paper.steps, own.steps) << name;
    EXPECT_EQ(paper.batch_size, own.batch_size) << name;
  }
}

// A sampled fit's paper preset is one layer of kSampledWidth (two sampled layers of 200 let the
// spring's rollouts run away, docs/sampled.md); lean and --hidden stay as they are, and
// sampled+adam keeps the paper's widths for its Adam steps.
TEST(Presets, ASampledFitTakesOneWiderLayer) {
  const auto task = make_task("spring");
  const auto hidden = [&](const char* fit, Preset preset, std::optional<std::vector<int>> given) {
    RunOptions o{.task = "spring", .preset = preset, .hidden = given};
    o.task_settings["fit"] = fit;
    return resolve(*task, o).train.hidden;
  };
  EXPECT_EQ(hidden("sampled", Preset::kPaper, {}), (std::vector<int>{kSampledWidth}));
  EXPECT_EQ(hidden("sampled", Preset::kLean, {}), task->lean_hidden());
  EXPECT_EQ(hidden("sampled", Preset::kPaper, std::vector<int>{50, 50}),
            (std::vector<int>{50, 50}));
  EXPECT_EQ(hidden("sampled+adam", Preset::kPaper, {}), (std::vector<int>{200, 200}));
}

// Lean changes the widths only, and to a smaller model on every swept task but three-body
// (whose smaller models' energy error blew up on some seed: its lean model is the paper's).
TEST(Presets, LeanIsASmallerModelWithEverythingElseThePapers) {
  for (const std::string& name : testing::state_tasks()) {
    const auto task = make_field_task(name);
    const TrainConfig paper = train_config(*task, Preset::kPaper),
                      lean = train_config(*task, Preset::kLean);
    EXPECT_EQ(lean.hidden, task->lean_hidden()) << name;
    const int dim = int(task->build_dataset(0).train_x.cols());
    if (name == "three-body") {
      EXPECT_EQ(lean.hidden, paper.hidden);
    } else {
      EXPECT_LT(hnn_parameters(dim, lean.hidden), hnn_parameters(dim, paper.hidden)) << name;
    }
    EXPECT_EQ(lean.steps, paper.steps) << name;
    EXPECT_EQ(lean.batch_size, paper.batch_size) << name;
    EXPECT_EQ(lean.learning_rate, paper.learning_rate) << name;
    EXPECT_EQ(lean.weight_decay, paper.weight_decay) << name;
  }
  // Not swept (10 minutes a run): its lean model is the paper's.
  const auto pixel = make_task("pixel-pendulum");
  EXPECT_EQ(train_config(*pixel, Preset::kLean).hidden, pixel->train_config().hidden);
}

TEST(Presets, AnUnknownPresetIsRefusedByName) {
  try {
    parse_preset("tiny");
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "preset must be paper or lean, got 'tiny'");
  }
  EXPECT_THROW(parse_preset("Lean"), Error);  // names are exact
  EXPECT_EQ(parse_preset("lean"), Preset::kLean);
  EXPECT_EQ(to_string(Preset::kLean), "lean");
}

// A run records its preset and trains the preset's widths unless --hidden says otherwise.
TEST(Presets, RunsUseTheLeanWidthsUnlessHiddenOverrides) {
  const auto task = make_task("spring");
  const std::vector<int> lean = task->lean_hidden();
  std::string lean_text;
  for (int w : lean) lean_text += (lean_text.empty() ? "" : "-") + std::to_string(w);

  TempDir dir("runs");
  RunOptions o = testing::small_run("spring", "hnn", dir / "lean", 3);
  o.hidden.reset();
  o.preset = Preset::kLean;
  const nlohmann::json m = run_training(o);
  EXPECT_EQ(m["hidden"], lean_text);
  EXPECT_EQ(m["preset"], "lean");
  EXPECT_EQ(read_json(dir / "lean" / "metrics.json")["preset"], "lean");

  o.out = dir / "override";
  o.hidden = std::vector<int>{8, 8, 8};
  const nlohmann::json overridden = run_training(o);
  EXPECT_EQ(overridden["hidden"], "8-8-8");
  EXPECT_EQ(overridden["preset"], "lean");

  o.out = dir / "paper";
  o.hidden.reset();
  o.preset = Preset::kPaper;
  o.model = nn::ModelKind::kBaseline;
  EXPECT_EQ(run_training(o)["hidden"], "200-200");
}

// The preset travels with a checkpoint, so a resumed run reports the same one.
TEST(Presets, ResumeOptionsKeepThePreset) {
  TempDir dir("run");
  RunOptions o = testing::small_run("spring", "hnn", dir / "run", 4);
  o.preset = Preset::kLean;
  run_training(o);
  const RunOptions resumed = resume_options(dir / "run");
  EXPECT_EQ(resumed.preset, Preset::kLean);
  EXPECT_EQ(*resumed.hidden, (std::vector<int>{16, 16}));  // the widths the run trained
}

}  // namespace
}  // namespace hnn::tasks
