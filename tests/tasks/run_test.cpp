// Run folders end to end on tiny settings: metrics.json complete and parseable, loss_curve.csv
// and rollout.csv with their documented headers, params.bin loadable, evaluation reproducible,
// runs deterministic per seed in float and double, and Table 1 from several runs.

#include "tasks/run.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tasks/experiments/registry.h"
#include "tasks/report/table1.h"
#include "tasks/studies/published.h"
#include "tasks/studies/reproduce.h"
#include "tasks/task.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::read_json;
using testing::read_lines;
using testing::read_text;
using testing::split_csv;
using testing::TempDir;

struct TaskShape {
  std::string task;
  int dim;
  long n_train, n_test;
  int rollout_points;
  double t_end;
};

// gtest names a parameter by its task (not by its bytes) in test listings and failures.
void PrintTo(const TaskShape& shape, std::ostream* os) { *os << shape.task; }

const TaskShape kShapes[] = {{"spring", 2, 750, 750, 100, 20.0},
                             {"pendulum", 2, 1125, 1125, 100, 20.0},
                             {"real-pendulum", 2, 444, 111, 100, 20.0},
                             {"two-body", 8, 40000, 10000, 1000, 20.0},
                             {"three-body", 12, 80000, 20000, 100, 20.0}};

// Every metric issue 5 requires, each a finite number (or the right string).
void expect_complete_metrics(const json& m, const std::string& task, const std::string& model,
                             std::uint64_t seed, int steps, const std::string& dtype) {
  for (const std::string& key : testing::numeric_metric_keys()) {
    ASSERT_TRUE(m.contains(key)) << key;
    ASSERT_TRUE(m[key].is_number()) << key << " = " << m[key].dump();
    EXPECT_TRUE(std::isfinite(m[key].get<double>())) << key;
  }
  EXPECT_EQ(m["task"], task);
  EXPECT_EQ(m["model"], model);
  EXPECT_EQ(m["seed"].get<std::uint64_t>(), seed);
  EXPECT_EQ(m["steps"].get<int>(), steps);
  EXPECT_EQ(m["dtype"], dtype);
  for (const char* key : {"train_loss", "test_loss", "energy_mse"}) {
    EXPECT_GT(m[key].get<double>(), 0) << key;
    EXPECT_GT(m[std::string(key) + "_se"].get<double>(), 0) << key;
    EXPECT_LT(m[std::string(key) + "_se"].get<double>(), m[key].get<double>()) << key;
  }
  EXPECT_GE(m["train_seconds"].get<double>(), 0);
  EXPECT_GT(m["curve_seconds"].get<double>(), 0);  // the loss curve's points, off the train clock
}

// loss_curve.csv: "step,train_loss,test_loss", one row per recorded step, the last one `steps`.
void expect_loss_curve(const fs::path& path, int steps) {
  const std::vector<std::string> lines = read_lines(path);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "step,train_loss,test_loss");
  long previous = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> cells = split_csv(lines[i]);
    ASSERT_EQ(cells.size(), 3u) << lines[i];
    const long step = std::stol(cells[0]);
    EXPECT_GT(step, previous) << lines[i];
    previous = step;
    EXPECT_TRUE(std::isfinite(std::stod(cells[1]))) << lines[i];
    EXPECT_TRUE(std::isfinite(std::stod(cells[2]))) << lines[i];
  }
  EXPECT_EQ(previous, steps);
}

std::string rollout_header(int dim) {
  std::string h = "source,traj,t";
  for (int k = 0; k < dim; ++k) h += fmt::format(",x_{}", k);
  return h + ",energy,learned_h";
}

// rollout.csv: the documented header, per trajectory (15) a block of points rows of the truth
// and one of the model, times from 0 to t_end, the true energy in every truth row, the learned H
// exactly in the rows of an HNN's prediction.
void expect_rollout_csv(const fs::path& path, const TaskShape& shape, const std::string& model) {
  const std::vector<std::string> lines = read_lines(path);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], rollout_header(shape.dim));
  const auto points = std::size_t(shape.rollout_points);
  ASSERT_EQ(lines.size(), 1u + 2 * 15u * points);
  const std::size_t cells_per_row = 3 + std::size_t(shape.dim) + 2;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> cells = split_csv(lines[i]);
    ASSERT_EQ(cells.size(), cells_per_row) << "line " << i << ": " << lines[i];
    const std::size_t block = (i - 1) / points, k = (i - 1) % points;
    const bool truth = block % 2 == 0;
    ASSERT_EQ(cells[0], truth ? "true" : model) << "line " << i;
    ASSERT_EQ(std::stoi(cells[1]), int(block / 2)) << "line " << i;
    EXPECT_NEAR(std::stod(cells[2]), shape.t_end * double(k) / double(points - 1), 1e-6) << i;
    if (truth) {
      EXPECT_FALSE(cells[3 + std::size_t(shape.dim)].empty()) << "energy, line " << i;
    }
    if (truth || model != "hnn") {
      EXPECT_TRUE(cells.back().empty()) << "learned_h of the truth or a baseline, line " << i;
    } else if (!cells[3].empty()) {  // a prediction: its H too
      EXPECT_FALSE(cells.back().empty()) << "learned_h, line " << i;
    }
  }
}

class RunFolder : public ::testing::TestWithParam<TaskShape> {};

TEST_P(RunFolder, HoldsCompleteMetricsCurvesRolloutsAndLoadableParameters) {
  const TaskShape& shape = GetParam();
  TempDir dir("run");
  const json returned = run_training(testing::small_run(shape.task, "hnn", dir.path(), 10));
  for (const char* file : {"metrics.json", "loss_curve.csv", "rollout.csv", "params.bin"})
    EXPECT_TRUE(fs::is_regular_file(dir / file)) << file;
  const json m = read_json(dir / "metrics.json");
  EXPECT_EQ(m, returned);
  expect_complete_metrics(m, shape.task, "hnn", 0, 10, "double");
  EXPECT_EQ(m["n_train"].get<long>(), shape.n_train);
  EXPECT_EQ(m["n_test"].get<long>(), shape.n_test);
  EXPECT_EQ(m["hidden"], "16-16");
  EXPECT_EQ(m["n_rollouts"].get<int>() + int(m["rollout_failures"].size()), 15);
  EXPECT_EQ(m["rollouts"], 15);
  // Every rollout metric has a standard error and a count; the floor is below the model's.
  for (const char* key : {"energy_mse", "state_mse", "relative_error_geomean",
                          "relative_error_floor", "valid_prediction_time"}) {
    EXPECT_TRUE(m.contains(std::string(key) + "_se")) << key;
    EXPECT_EQ(m[std::string(key) + "_count"], m["n_rollouts"]) << key;
  }
  EXPECT_LT(m["relative_error_floor"].get<double>(), m["relative_error_geomean"].get<double>());
  // Three bodies: the errors at early times, where chaos has not yet taken over.
  EXPECT_EQ(m.contains("state_mse_t1"), shape.task == "three-body");
  expect_loss_curve(dir / "loss_curve.csv", 10);
  expect_rollout_csv(dir / "rollout.csv", shape, "hnn");

  const LoadedRun run = load_run(dir.path());
  EXPECT_EQ(run.settings.task, shape.task);
  EXPECT_EQ(run.settings.model, nn::ModelKind::kHnn);
  EXPECT_EQ(run.run->dynamics().name(), "hnn");
  EXPECT_EQ(run.run->dynamics().dim(), shape.dim);
  EXPECT_EQ(run.run->rollout_states(1000).cols(), shape.dim);
  // The saved parameters reproduce the run's numbers exactly.
  const json again = evaluate_run(dir.path(), "", /*write_files=*/false);
  for (const char* key :
       {"train_loss", "train_loss_se", "test_loss", "test_loss_se", "energy_mse", "energy_mse_se"})
    EXPECT_EQ(again[key].get<double>(), m[key].get<double>()) << key;
}

INSTANTIATE_TEST_SUITE_P(EveryTask, RunFolder, ::testing::ValuesIn(kShapes),
                         [](const ::testing::TestParamInfo<TaskShape>& info) {
                           std::string name = info.param.task;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

TEST(RunFolderBaseline, HasNoLearnedHamiltonianButEverythingElse) {
  TempDir dir("run");
  const json m = run_training(testing::small_run("spring", "baseline", dir.path(), 10));
  expect_complete_metrics(m, "spring", "baseline", 0, 10, "double");
  expect_rollout_csv(dir / "rollout.csv", kShapes[0], "baseline");
  EXPECT_EQ(load_run(dir.path()).run->dynamics().name(), "baseline");
}

TEST(EvaluateRun, WriteFilesRecreatesTheSameRollouts) {
  TempDir dir("run");
  run_training(testing::small_run("pendulum", "hnn", dir.path(), 5));
  const std::string before = read_text(dir / "rollout.csv");
  fs::remove(dir / "rollout.csv");
  evaluate_run(dir.path(), "", /*write_files=*/false);
  EXPECT_FALSE(fs::exists(dir / "rollout.csv"));
  evaluate_run(dir.path(), "", /*write_files=*/true);
  EXPECT_EQ(read_text(dir / "rollout.csv"), before);
}

TEST(EvaluateRun, RejectsAFolderThatIsNoRun) {
  TempDir dir("empty");
  EXPECT_THROW(evaluate_run(dir.path(), "", false), std::exception);
  std::ofstream(dir / "metrics.json") << "{\"task\": \"spring\"}";
  EXPECT_THROW(load_run(dir.path()), std::exception);
}

// Everything but timings.
json without_timings(json m) {
  for (const char* key : {"train_seconds", "curve_seconds", "eval_seconds", "data_seconds"})
    m.erase(key);
  return m;
}

TEST(RunDeterminism, SameSeedSameNumbersAndFilesOtherSeedOtherNumbers) {
  for (const char* task : {"spring", "two-body"}) {  // full batch, and minibatches of 200
    TempDir a("a"), b("b"), c("c");
    const json ma = run_training(testing::small_run(task, "hnn", a.path(), 8));
    const json mb = run_training(testing::small_run(task, "hnn", b.path(), 8));
    EXPECT_EQ(without_timings(ma).dump(), without_timings(mb).dump()) << task;
    for (const char* file : {"loss_curve.csv", "rollout.csv", "params.bin"})
      EXPECT_EQ(read_text(a / file), read_text(b / file)) << task << " " << file;
    RunOptions other = testing::small_run(task, "hnn", c.path(), 8);
    other.seed = 1;
    const json mc = run_training(other);
    EXPECT_NE(mc["test_loss"].get<double>(), ma["test_loss"].get<double>()) << task;
    EXPECT_NE(mc["energy_mse"].get<double>(), ma["energy_mse"].get<double>()) << task;
  }
}

TEST(RunDtype, FloatAndDoubleBothRunAndAgree) {
  TempDir f("float"), d("double");
  RunOptions in_float = testing::small_run("spring", "hnn", f.path(), 20);
  in_float.dtype = Dtype::kFloat;
  const json mf = run_training(in_float);
  const json md = run_training(testing::small_run("spring", "hnn", d.path(), 20));
  expect_complete_metrics(mf, "spring", "hnn", 0, 20, "float");
  expect_complete_metrics(md, "spring", "hnn", 0, 20, "double");
  // Same initialisation and data; float rounding only.
  EXPECT_NEAR(mf["test_loss"].get<double>(), md["test_loss"].get<double>(),
              1e-3 * md["test_loss"].get<double>());
  // A float run's parameters load back (cast to double) and reproduce its metrics.
  const json again = evaluate_run(f.path(), "", false);
  EXPECT_EQ(again["dtype"], "float");
  EXPECT_EQ(again["test_loss"].get<double>(), mf["test_loss"].get<double>());
  EXPECT_EQ(again["energy_mse"].get<double>(), mf["energy_mse"].get<double>());
}

TEST(RunDataFile, RealPendulumTrainsAndEvaluatesOnAnotherFile) {
  TempDir dir("run");
  // The first 101 measurements of the shipped file: 100 differences, 80 train and 20 test.
  const std::vector<std::string> lines =
      read_lines(fs::path(HNN_SOURCE_DIR) / "data/lipson/real_pend_h_1.txt");
  ASSERT_GT(lines.size(), 102u);
  const fs::path file = dir / "short.txt";
  {
    std::ofstream out(file, std::ios::binary);
    for (std::size_t i = 0; i < 102; ++i) out << lines[i] << "\n";  // header + 101 rows
  }
  RunOptions o = testing::small_run("real-pendulum", "baseline", dir / "out", 5);
  o.data_file = file.string();
  const json m = run_training(o);
  EXPECT_EQ(m["n_train"].get<long>(), 80);
  EXPECT_EQ(m["n_test"].get<long>(), 20);
  EXPECT_EQ(m["data_file"], file.string());
  // evaluate_run finds the same file in metrics.json.
  EXPECT_EQ(evaluate_run(dir / "out", "", false)["test_loss"].get<double>(),
            m["test_loss"].get<double>());
  // Another file given to evaluate_run changes the test set, and so the loss.
  EXPECT_NE(evaluate_run(dir / "out",
                         (fs::path(HNN_SOURCE_DIR) / "data/lipson/real_pend_h_1.txt").string(),
                         false)["test_loss"]
                .get<double>(),
            m["test_loss"].get<double>());
}

TEST(Reproduce, TableAveragesSeedsAndCarriesThePapersValues) {
  TempDir dir("results");
  ReproduceOptions o;
  o.tasks = {"real-pendulum"};
  o.seeds = 2;
  o.steps = 5;
  o.out = dir.path();
  o.quiet = true;
  const json table = reproduce(o);
  EXPECT_EQ(read_json(dir / "table1.json"), table);
  ASSERT_EQ(table.size(), 2u);
  const json published = read_published(published_path());
  for (const json& row : table) {
    const std::string model = row["model"];
    EXPECT_EQ(row["task"], "real-pendulum");
    EXPECT_EQ(row["seeds"].get<int>(), 2);
    EXPECT_EQ(row["steps"].get<int>(), 5);
    const json s0 = read_json(dir / "real-pendulum" / model / "seed-0" / "metrics.json");
    const json s1 = read_json(dir / "real-pendulum" / model / "seed-1" / "metrics.json");
    for (const char* key : {"train_loss", "test_loss", "energy_mse", "energy_mse_se"}) {
      EXPECT_NEAR(row[key].get<double>(), (s0[key].get<double>() + s1[key].get<double>()) / 2,
                  1e-12 * std::abs(row[key].get<double>()))
          << model << " " << key;
    }
    const PaperRow paper = paper_row(published, "real-pendulum", parse_model(model));
    EXPECT_EQ(row["paper_train_loss"].get<double>(), paper.train_loss.mean);
    EXPECT_EQ(row["paper_test_loss"].get<double>(), paper.test_loss.mean);
    EXPECT_EQ(row["paper_energy_mse"].get<double>(), paper.energy_mse.mean);
    EXPECT_EQ(row["paper_energy_mse_se"].get<double>(), paper.energy_mse.se);
  }
  const std::string md = read_text(dir / "table1.md");
  EXPECT_NE(md.find("| real-pendulum |"), std::string::npos) << md;
  EXPECT_NE(md.find("2.7455e-03"), std::string::npos) << md;  // the paper's baseline train loss
  EXPECT_NE(md.find("9.2376e-03"), std::string::npos) << md;  // ... and HNN train loss
  // The reversibility report over the runs: a row per model, seed 0's run.
  const std::string rev = read_text(dir / "reversibility.md");
  EXPECT_NE(rev.find("| real-pendulum | baseline |"), std::string::npos) << rev;
  EXPECT_NE(rev.find("| real-pendulum | hnn |"), std::string::npos) << rev;
  EXPECT_EQ(read_json(dir / "reversibility.json").size(), 2u);
}

TEST(Table1Markdown, OneRowOfOursAndOneOfThePapersPerTask) {
  const json base = {{"task", "spring"},
                     {"model", "baseline"},
                     {"steps", 2000},
                     {"dtype", "double"},
                     {"train_loss", 0.037},
                     {"train_loss_se", 0.0019},
                     {"test_loss", 0.036},
                     {"test_loss_se", 0.0018},
                     {"energy_mse", 0.17},
                     {"energy_mse_se", nullptr},
                     {"train_seconds", 12.0},
                     {"paper_train_loss", 3.7134e-2},
                     {"paper_train_loss_se", 1.9e-3},
                     {"paper_test_loss", 3.6656e-2},
                     {"paper_test_loss_se", 1.9e-3},
                     {"paper_energy_mse", 1.7077e-1},
                     {"paper_energy_mse_se", 2.1e-2}};
  json hnn = base;
  hnn["model"] = "hnn";
  hnn["energy_mse"] = nullptr;  // every rollout failed: shown as n/a, not 0
  const std::string md = table1_markdown(json::array({base, hnn}), 61.5);
  EXPECT_NE(md.find("| spring | ours (2000 steps, double) | 3.7000e-02 ± 1.9e-03 / 3.7000e-02 ± "
                    "1.9e-03 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("1.7000e-01 / n/a"), std::string::npos) << md;  // no standard error
  EXPECT_NE(md.find("| | *paper* | 3.7134e-02 ± 1.9e-03"), std::string::npos) << md;
  EXPECT_NE(md.find("61.5 s"), std::string::npos) << md;
  // With the rollouts' count in the rows, the table states it beside the paper's 15.
  json counted = hnn;
  counted["rollouts"] = 100;
  const std::string with_count = table1_markdown(json::array({base, counted}), 61.5);
  EXPECT_NE(with_count.find("| spring | ours (2000 steps, double, 100 rollouts) |"),
            std::string::npos)
      << with_count;
  EXPECT_NE(with_count.find("| | *paper* (15 rollouts) |"), std::string::npos) << with_count;
}

// A run that ends no better than it started is warned about, in metrics.json's "warnings".
TEST(RunWarnings, ALossThatDidNotFallOrAnR2NearZeroIsOneSentenceEach) {
  const std::vector<CurvePoint> fell = {{20, 1.0, 0.5}, {200, 0.01, 0.02}};
  const std::vector<CurvePoint> rose = {{20, 1.0, 0.5}, {200, 0.9, 0.6}};
  EXPECT_TRUE(run_warnings(fell, {{"test_r2", 0.97}}).empty());
  const std::vector<std::string> warned = run_warnings(rose, {{"test_r2", 0.02}});
  ASSERT_EQ(warned.size(), 2u);
  EXPECT_EQ(warned[0],
            "the test loss did not fall: 0.5 at step 20, 0.6 at the last step (200); the run "
            "ended no better than it started (a smaller --lr may help)");
  EXPECT_EQ(warned[1],
            "the test R^2 is 0.02, below 0.1: the model explains almost none of the spread of the "
            "test dx/dt");
  // Without a test loss, the training loss; without an R^2 (the pixel pendulum), the curve only;
  // without a curve (a run evaluated again), the R^2 only.
  const std::vector<CurvePoint> no_test = {{1, 1.0, NAN}, {2, 1.0, NAN}};
  EXPECT_EQ(run_warnings(no_test, json::object()).size(), 1u);
  EXPECT_NE(run_warnings(no_test, json::object())[0].find("training loss"), std::string::npos);
  EXPECT_TRUE(run_warnings(fell, {{"test_r2", nullptr}}).empty());
  EXPECT_EQ(run_warnings({}, {{"test_r2", -3.0}}).size(), 1u);
}

// A model whose training loss ends far below the true system's own through the same integrator
// learned a motion the integrator can follow, not the true one (the magnet pendulum's windows
// through classic RK4 at the peer's step: the truth's loss 86.5 where the model's is 0.03).
TEST(RunWarnings, ATruthLossFarAboveTheTrainingsSaysTheIntegratorCannotFollow) {
  const std::vector<CurvePoint> curve = {{20, 1.0, 0.5}, {200, 0.03, 0.02}};
  const std::vector<std::string> warned = run_warnings(curve, {{"truth_rollout_loss", 86.5}});
  ASSERT_EQ(warned.size(), 1u);
  EXPECT_TRUE(
      warned[0].starts_with("the true system's own rollout loss through the training's "
                            "integrator is 86.5, over 10 times the training's last loss "
                            "(0.03)"))
      << warned[0];
  // At the floor (the gyroscope's 2.8e-5 against 3.1e-5), or without a curve: nothing.
  EXPECT_TRUE(
      run_warnings({{20, 1.0, 0.5}, {200, 3.1e-5, 3.2e-5}}, {{"truth_rollout_loss", 2.8e-5}})
          .empty());
  EXPECT_TRUE(run_warnings({}, {{"truth_rollout_loss", 86.5}}).empty());
}

// A diverging run (a learning rate of 1e3) ends with its warning in metrics.json; a good one
// with an empty list.
TEST(RunWarnings, ReachMetricsJson) {
  TempDir dir("warnings");
  RunOptions o = testing::small_run("spring", "hnn", dir / "wild", 30);
  o.learning_rate = 1e3;
  const json wild = run_training(o);
  EXPECT_FALSE(wild["warnings"].empty()) << wild.dump(1);
  EXPECT_EQ(read_json(dir / "wild" / "metrics.json")["warnings"], wild["warnings"]);
  o = testing::small_run("spring", "hnn", dir / "calm", 200);
  EXPECT_EQ(run_training(o)["warnings"], json::array()) << "a healthy run was warned about";
}

}  // namespace
}  // namespace hnn::tasks
