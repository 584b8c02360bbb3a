// The rollout loss on the field tasks: stretches from each task's trajectories (split as its
// dataset is), a run that learns through leapfrog and the midpoint rule, and the settings that
// are refused before a run exists.

#include <gtest/gtest.h>

#include <cmath>

#include "physics/oscillators.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/field/field_training.h"
#include "tasks/run.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

RunSettings settings(const std::string& task, nlohmann::json task_settings, int steps = 10) {
  RunOptions o = testing::small_run(task, "hnn", "unused", steps);
  o.hidden = std::vector<int>{32, 32};
  o.task_settings = std::move(task_settings);
  return resolve(*make_task(task), o);
}

TEST(FieldRollout, StretchesFollowEachTasksTrajectoriesAndSplit) {
  const auto spring = make_field_task("spring");
  const RunSettings s = settings("spring", {{"sample_dt", 0.5}});
  const Dataset d = spring->build_dataset(s);
  const std::optional<SplitStretches> st = spring->stretches(s, d);
  ASSERT_TRUE(st.has_value());
  EXPECT_EQ(st->train.size(), 25u);  // 50 trajectories, the first half train
  EXPECT_EQ(st->test.size(), 25u);
  EXPECT_EQ(st->train[0].x.rows(), 7);  // t = 0, 0.5, ..., 3
  EXPECT_DOUBLE_EQ(st->train[0].t(1), 0.5);
  EXPECT_EQ(st->train[3].x, d.train_x.middleRows(21, 7));
  EXPECT_EQ(st->test[0].x, d.test_x.topRows(7));

  const auto real = make_field_task("real-pendulum");
  const RunSettings r = settings("real-pendulum", nlohmann::json::object());
  const Dataset rd = real->build_dataset(r);
  const std::optional<SplitStretches> rs = real->stretches(r, rd);
  ASSERT_TRUE(rs.has_value());
  Eigen::Index train_rows = 0, test_rows = 0;
  for (const Stretch& x : rs->train) train_rows += x.x.rows();
  for (const Stretch& x : rs->test) test_rows += x.x.rows();
  EXPECT_EQ(train_rows, rd.train_x.rows());
  EXPECT_EQ(test_rows, rd.test_x.rows());
  EXPECT_EQ(rs->train[0].x.row(1), rd.train_x.row(1));
  EXPECT_GT(rs->train[0].t(1), rs->train[0].t(0));

  const auto three = make_field_task("three-body");
  const RunSettings t = settings("three-body", {{"setup", "srnn"}});
  const Dataset td = three->build_dataset(t);
  EXPECT_EQ(td.train_x.rows(), 100 * 10);
  EXPECT_EQ(td.test_x.rows(), 32 * 10);
  EXPECT_EQ(three->stretches(t, td)->test[5].t(9), 9.0);

  EXPECT_FALSE(make_field_task("damped-spring")->stretches(s, d).has_value());
}

// Coarse noisy spring (dt = 0.5): the rollout loss falls through leapfrog and through the
// implicit midpoint rule, and the run reports how it trained.
TEST(FieldRollout, ARolloutRunOnTheSpringLearns) {
  for (const char* integrator : {"leapfrog", "midpoint"}) {
    const RunSettings s = settings(
        "spring",
        {{"sample_dt", 0.5}, {"loss", "rollout"}, {"horizon", 3}, {"integrator", integrator}}, 150);
    const auto task = make_field_task("spring");
    const std::unique_ptr<TaskRun> run = task->open(s);
    const TrainResult r = run->train({.quiet = true});
    ASSERT_GE(r.curve.size(), 2u);
    EXPECT_LT(r.curve.back().train_loss, 0.3 * r.curve.front().train_loss) << integrator;
    const nlohmann::json m = run->evaluate(nullptr);
    EXPECT_EQ(m["training"], nlohmann::json({{"loss", "rollout"},
                                             {"integrator", integrator},
                                             {"horizon", 3},
                                             {"dt", "sampling interval"}}));
    EXPECT_LT(m["stretch_state_mse"].get<double>(), 0.2) << m.dump();
    EXPECT_EQ(m["n_stretches"], 25);
  }
}

TEST(FieldRollout, SubStepsDivideTheIntervalOrAreRefused) {
  const auto task = make_field_task("spring");
  EXPECT_NO_THROW(task->open(settings(
      "spring", {{"sample_dt", 0.5}, {"loss", "rollout"}, {"dt", 0.25}, {"integrator", "rk4"}})));
  try {
    task->open(settings("spring", {{"sample_dt", 0.5}, {"loss", "rollout"}, {"dt", 0.3}}));
    FAIL() << "dt 0.3 was accepted for an interval of 0.5";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "--dt 0.3 does not divide the sampling interval (0.5) into whole steps: use the "
                 "interval divided by a whole number");
  }
  EXPECT_THROW(settings("spring", {{"horizon", 2}}), Error);
  EXPECT_THROW(task->open(settings("spring", {{"loss", "rollout"}, {"horizon", 30}})), Error);
  EXPECT_THROW(
      make_field_task("damped-spring")->open(settings("damped-spring", {{"loss", "rollout"}})),
      Error);
}

// The spring H = q^2 + p^2 sampled exactly every `interval` (q = r cos(2t + a), p = -r sin(2t +
// a)): 6 trajectories of 9 samples each, the first 4 for training.
SplitStretches exact_spring(double interval) {
  SplitStretches st;
  for (int i = 0; i < 6; ++i) {
    const double r = 0.3 + 0.2 * i, a = 0.9 * i;
    Stretch s{Eigen::VectorXd(9), Batch(9, 2)};
    for (int k = 0; k < 9; ++k) {
      const double t = k * interval;
      s.t(k) = t;
      s.x.row(k) << r * std::cos(2 * t + a), -r * std::sin(2 * t + a);
    }
    (i < 4 ? st.train : st.test).push_back(std::move(s));
  }
  return st;
}

// The truth's rollout loss is its integrator's error alone: on exact samples, RK4's global error
// falls as h^4, so half the step takes the L1 loss down 16-fold; the midpoint has none.
TEST(FieldRollout, TheTruthsRolloutLossIsTheIntegratorsErrorAndFallsWithItsStep) {
  const physics::Spring spring;  // H = q^2 + p^2, the samples' motion
  const SplitStretches st = exact_spring(0.1);
  const auto truth_loss = [&](double dt, RolloutIntegrator integrator) {
    const RolloutLossConfig loss{.rollout = true,
                                 .horizon = 4,
                                 .integrator = integrator,
                                 .dt = dt,
                                 .norm = RolloutNorm::kL1};
    return FieldTraining(loss, &st, TrainConfig{}, "spring").truth_loss(spring);
  };
  const double whole = truth_loss(0, RolloutIntegrator::kRk4);
  const double half = truth_loss(0.05, RolloutIntegrator::kRk4);
  EXPECT_GT(whole, 1e-8);
  EXPECT_LT(whole, 1e-4);
  EXPECT_NEAR(whole / half, 16.0, 2.0);
  EXPECT_TRUE(std::isnan(truth_loss(0, RolloutIntegrator::kMidpoint)));
}

}  // namespace
}  // namespace hnn::tasks
