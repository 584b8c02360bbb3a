// The metrics for comparing model families (issue 18, section 4): every field task's rollouts
// (100 by default, the settings "rollouts" and "t_end" through one code path), the floor a
// perturbed truth reaches, short-horizon errors, and a standard error and a count on each.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/evaluate/state_errors.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

using nlohmann::json;
using testing::TempDir;

// The message of the Error that checking `settings` on `task` throws ("" when none).
std::string settings_error(const std::string& task, const json& settings) {
  try {
    make_field_task(task)->check_task_settings(settings);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(RolloutSettings, EveryFieldTaskRollsOutAtLeastAHundredByDefault) {
  for (const std::string& name : task_names()) {
    if (name == "pixel-pendulum" || name == "data") continue;
    const std::unique_ptr<FieldTask> task = make_field_task(name);
    EXPECT_GE(task->rollout_config(json::object()).trajectories, 100) << name;
  }
  // The real pendulum has 111 test states: all 100 are distinct measured ones.
  const std::unique_ptr<FieldTask> real = make_field_task("real-pendulum");
  std::mt19937_64 rng(0);
  const Batch x0 = real->rollout_states(real->build_dataset(0), 100, rng);
  ASSERT_EQ(x0.rows(), 100);
  for (Eigen::Index i = 1; i < x0.rows(); ++i) EXPECT_NE(x0.row(i), x0.row(i - 1)) << i;
}

TEST(RolloutSettings, CountAndSpanComeThroughOneCodePath) {
  for (const char* name : {"two-body", "double-pendulum", "damped-spring"}) {
    const std::unique_ptr<FieldTask> task = make_field_task(name);
    const RolloutConfig d = task->rollout_config(json::object());
    const RolloutConfig c = task->rollout_config({{"rollouts", 7}, {"t_end", d.t_end / 2}});
    EXPECT_EQ(c.trajectories, 7) << name;
    EXPECT_DOUBLE_EQ(c.t_end, d.t_end / 2) << name;
    // The sampling interval stays the default's.
    EXPECT_NEAR(c.t_end / (c.points - 1), d.t_end / (d.points - 1), 0.01 * d.t_end / d.points)
        << name;
    EXPECT_EQ(task->rollout_config({{"rollout_t_end", 3.0}}).t_end, 3.0) << name;
  }
  // Spring and pendulum: t_end is their trajectories' span; rollout_t_end is the rollouts'.
  const std::unique_ptr<FieldTask> spring = make_field_task("spring");
  EXPECT_EQ(spring->rollout_config({{"t_end", 6.0}}).t_end, 20.0);
  EXPECT_EQ(spring->rollout_config({{"rollout_t_end", 6.0}}).t_end, 6.0);
  // Three-body's horizons past a shorter span are dropped.
  const RolloutConfig three = make_field_task("three-body")->rollout_config({{"t_end", 1.5}});
  EXPECT_EQ(three.horizons, (std::vector<double>{0.5, 1.0}));
}

TEST(RolloutSettings, BadValuesGetOneLineNamingTheTaskAndTheSetting) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<json, std::string>> bad = {
      {{{"rollouts", 0}}, "two-body: rollouts must be an integer from 1 to 1000, got 0"},
      {{{"rollouts", -3}}, "two-body: rollouts must be an integer from 1 to 1000, got -3"},
      {{{"rollouts", 1.5}}, "two-body: rollouts must be an integer from 1 to 1000, got 1.5"},
      {{{"rollouts", "ten"}}, "two-body: rollouts must be an integer from 1 to 1000, got \"ten\""},
      {{{"rollouts", 1001}}, "two-body: rollouts must be an integer from 1 to 1000, got 1001"},
      {{{"t_end", 0}}, "two-body: t_end must be a finite number > 0, got 0"},
      {{{"t_end", -1.5}}, "two-body: t_end must be a finite number > 0, got -1.5"},
      {{{"t_end", inf}}, "two-body: t_end must be a finite number > 0, got null"},
      {{{"rollout_t_end", "x"}}, "two-body: rollout_t_end must be a finite number > 0, got \"x\""},
      {{{"t_end", 2}, {"rollout_t_end", 3}},
       "two-body: t_end and rollout_t_end both set the rollouts' span: give one"}};
  for (const auto& [settings, message] : bad)
    EXPECT_EQ(settings_error("two-body", settings), message) << settings.dump();
  EXPECT_EQ(settings_error("two-body", {{"rollouts", 1000}, {"t_end", 0.5}}), "");
  EXPECT_EQ(settings_error("spring", {{"rollout_t_end", 0}}),
            "spring: rollout_t_end must be a finite number > 0, got 0");
}

TEST(RolloutSettings, MoreRolloutsThanAMeasuredTaskHasStatesIsRefusedBeforeARunFolder) {
  TempDir dir("runs");
  RunOptions o = testing::small_run("real-pendulum", "baseline", dir / "run", 5);
  o.task_settings = {{"rollouts", 500}};
  try {
    run_training(o);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "real-pendulum: rollouts 500 is more than the 111 distinct initial states its data "
              "have");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "run"));
}

// Note [Perturbed truth]: the spring is linear, so a start moved by 1e-4 stays 1e-4 away; the
// three bodies amplify it.
TEST(RelativeErrorFloor, IsThePerturbedTruthsErrorAndGrowsWithChaos) {
  const std::unique_ptr<FieldTask> spring = make_field_task("spring");
  std::mt19937_64 rng(0);
  const Batch x0 = spring->rollout_states(spring->build_dataset(0), 10, rng);
  const LearnedField still{
      .field = [](double, const Batch& x, Batch& dxdt) { dxdt = Batch::Zero(x.rows(), x.cols()); }};
  RolloutConfig config{.trajectories = 10, .t_end = 5.0, .points = 51, .horizons = {0.25, 1.0}};
  const Rollouts r = make_rollouts(spring->truth(), still, x0, config);
  ASSERT_EQ(r.floor.size(), 10u);
  const RelativeError floor = relative_error_floor(r);
  EXPECT_EQ(floor.count, 10);
  EXPECT_GT(floor.geomean, 1e-6);
  EXPECT_LT(floor.geomean, 1e-3);
  EXPECT_GT(floor.geomean_se, 0);
  EXPECT_EQ(floor.censored, 10);  // never near 0.1
  // The horizons off the grid (0.25) are the truth's exact flow there.
  ASSERT_EQ(r.truth_at[0].rows(), 2);
  const Batch exact = *spring->truth().exact_flow(Batch(x0.row(0)), 0.25);
  EXPECT_LT((r.truth_at[0].row(0) - exact.row(0)).norm(), 1e-8);
  // The same draws for the same seed; none without a perturbation.
  EXPECT_EQ(make_rollouts(spring->truth(), still, x0, config).floor[3], r.floor[3]);
  config.perturbation = 0;
  EXPECT_TRUE(make_rollouts(spring->truth(), still, x0, config).floor.empty());

  const std::unique_ptr<FieldTask> three = make_field_task("three-body");
  const Batch y0 = three->rollout_states(three->build_dataset(0), 6, rng);
  const RolloutConfig c3{
      .trajectories = 6, .t_end = 20.0, .points = 101, .horizons = three->short_horizons()};
  const std::vector<HorizonError> h = horizon_errors(make_rollouts(three->truth(), still, y0, c3));
  ASSERT_EQ(h.size(), 4u);
  EXPECT_DOUBLE_EQ(h[0].t, 0.5);
  EXPECT_LT(h[0].floor.mean, 1e-3);
  EXPECT_GT(h[3].floor.mean, h[0].floor.mean);
}

// A briefly trained model is worse than the perturbed truth and better than nothing, and every
// rollout metric has a standard error and a count.
TEST(RelativeErrorFloor, LiesBelowATrainedModelsErrorAndAboveZero) {
  TempDir dir("runs");
  RunOptions o = testing::small_run("spring", "hnn", dir / "run", 300);
  o.task_settings = {{"rollouts", 12}, {"rollout_t_end", 5.0}};
  const json m = run_training(o);
  EXPECT_EQ(m["rollouts"], 12);
  const double floor = m["relative_error_floor"], model = m["relative_error_geomean"];
  EXPECT_GT(floor, 0);
  EXPECT_LT(floor * 10, model) << m.dump();
  EXPECT_LT(model, 1);
  const int n = m["n_rollouts"];
  EXPECT_EQ(n + int(m["rollout_failures"].size()), 12);
  for (const char* key : {"energy_mse", "state_mse", "relative_error_geomean",
                          "relative_error_floor", "valid_prediction_time"}) {
    ASSERT_TRUE(m[std::string(key) + "_se"].is_number()) << key;
    EXPECT_GT(m[std::string(key) + "_se"].get<double>(), 0) << key;
    EXPECT_EQ(m[std::string(key) + "_count"].get<int>(), n) << key;
  }
}

// Measured truth may miss samples: every metric skips them, and a path that follows the
// measurements exactly has no error.
TEST(FollowMeasured, SkipsMissingSamplesAndHasNoFloorOrEnergy) {
  const RolloutConfig config{.t_end = 1.0, .points = 11, .horizons = {0.2, 0.5}};
  // x(t) = x0 + t (1, 1): the field (1, 1).
  std::vector<Eigen::MatrixXd> paths;
  for (int i = 0; i < 3; ++i) {
    Eigen::MatrixXd p(11, 2);
    for (int k = 0; k < 11; ++k) p.row(k) << 1 + i + 0.1 * k, 2 + 0.1 * k;
    paths.push_back(p);
  }
  paths[1].row(5).setConstant(NAN);  // a dropped frame, at the 0.5 horizon
  const LearnedField exact{
      .field = [](double, const Batch& x, Batch& dxdt) { dxdt = Batch::Ones(x.rows(), x.cols()); }};
  const Rollouts r = follow_measured(paths, exact, config);
  EXPECT_TRUE(r.measured);
  EXPECT_TRUE(r.floor.empty());
  const json m = rollout_metrics(r);
  EXPECT_TRUE(m["energy_mse"].is_null());
  EXPECT_TRUE(m["relative_error_floor"].is_null());
  EXPECT_TRUE(m.contains("relative_error_floor_note"));
  EXPECT_LT(m["state_mse"].get<double>(), 1e-18);
  EXPECT_EQ(m["state_mse_count"], 3);
  EXPECT_DOUBLE_EQ(m["valid_prediction_time"].get<double>(), 1.0);  // never passes 0.1
  EXPECT_EQ(m["state_mse_t0.2_count"], 3);
  EXPECT_EQ(m["state_mse_t0.5_count"], 2);  // not measured on path 1
  // A horizon off the measured grid moves to the nearest measured time.
  const Rollouts moved =
      follow_measured(paths, exact, {.t_end = 1.0, .points = 11, .horizons = {0.26}});
  EXPECT_DOUBLE_EQ(moved.horizons[0], 0.3);
  EXPECT_DOUBLE_EQ(moved.truth_at[0](0, 0), 1.3);
}

}  // namespace
}  // namespace hnn::tasks
