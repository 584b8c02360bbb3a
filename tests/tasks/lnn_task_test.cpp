// The Lagrangian NN as a model the program trains (--model lnn) on the double-pendulum task of
// its paper, in angles and angular velocities: short runs that learn, its energy metric, and the
// models and settings the task refuses; its baseline on accelerations alone (--baseline-output).

#include <gtest/gtest.h>

#include <cmath>

#include "physics/double_pendulum.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

using testing::TempDir;

TEST(DoublePendulumTask, IsTheLnnPapersSamplingWithExactAccelerations) {
  const Dataset d = build_dataset("double-pendulum", 3);
  EXPECT_EQ(d.train_x.rows(), 20000);
  EXPECT_EQ(d.test_x.rows(), 5000);
  EXPECT_GE(d.train_x.leftCols(2).minCoeff(), 0.0);
  EXPECT_LT(d.train_x.leftCols(2).maxCoeff(), 2 * M_PI);
  EXPECT_LE(d.train_x.rightCols(2).cwiseAbs().maxCoeff(), 10.0);
  Batch f;
  physics::DoublePendulumVelocities().vector_field(d.test_x, f);
  EXPECT_EQ(f, d.test_dxdt);
}

TEST(DoublePendulumTask, TrainsAnLnnAndReportsTheEnergyErrorAtTheEnd) {
  TempDir dir("runs");
  RunOptions o = testing::small_run("double-pendulum", "lnn", dir / "lnn", 150);
  o.task_settings = {{"rollouts", 3}, {"t_end", 2.0}};
  const nlohmann::json m = run_training(o);
  ASSERT_TRUE(m.contains("energy_error_end")) << m.dump();
  EXPECT_EQ(m["energy_error_end_count"].get<int>() + int(m["rollout_failures"].size()), 3);
  EXPECT_TRUE(std::isfinite(m["test_loss"].get<double>()));
  // Saved and loaded as any run.
  EXPECT_EQ(evaluate_run(dir / "lnn", "", false)["test_loss"], m["test_loss"]);
}

TEST(DoublePendulumTask, RefusesModelsThatNeedMomentaAndUnknownSettings) {
  TempDir dir("runs");
  for (const char* model : {"hnn", "dhnn"}) {
    RunOptions o = testing::small_run("double-pendulum", model, dir / model, 5);
    try {
      run_training(o);
      FAIL() << model << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("its models: lnn, baseline"), std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / model));
  }
  RunOptions o = testing::small_run("spring", "lnn", dir / "spring", 5);
  EXPECT_THROW(run_training(o), Error);
  o = testing::small_run("double-pendulum", "lnn", dir / "bad", 5);
  o.task_settings = {{"rollout", 3}};
  EXPECT_THROW(run_training(o), Error);
  o.task_settings = {{"rollouts", 0}};
  EXPECT_THROW(run_training(o), Error);
}

TEST(DoublePendulumTask, TrainsABaselineOnAccelerationsAloneAndRefusesItElsewhere) {
  TempDir dir("runs");
  RunOptions o = testing::small_run("double-pendulum", "baseline", dir / "acc", 20);
  o.task_settings = {{"rollouts", 2}, {"t_end", 1.0}, {"baseline_output", "accelerations"}};
  const nlohmann::json m = run_training(o);
  EXPECT_TRUE(std::isfinite(m["test_loss"].get<double>())) << m.dump();
  // Its run loads with the same shape of MLP (4 outputs would not fit its 2).
  EXPECT_EQ(evaluate_run(dir / "acc", "", false)["test_loss"], m["test_loss"]);
  const auto refused = [&](const std::string& task, const std::string& model,
                           const std::string& value, const std::string& why) {
    RunOptions bad = testing::small_run(task, model, dir / "bad", 5);
    bad.task_settings = {{"baseline_output", value}};
    try {
      run_training(bad);
      ADD_FAILURE() << task << " " << model << " " << value << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
  };
  refused("double-pendulum", "lnn", "accelerations", "applies to --model baseline only");
  refused("spring", "baseline", "accelerations", "needs a state (q, dq/dt)");
  refused("double-pendulum", "baseline", "forces", "must be field or accelerations");
}

}  // namespace
}  // namespace hnn::tasks
