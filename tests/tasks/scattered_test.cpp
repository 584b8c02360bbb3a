// The sampled-HNN paper's protocols as tasks (tasks/experiments/scattered.cpp): their data, their
// metric (the relative L2 error of H up to a constant, tasks/evaluate/hamiltonian_error.h), runs
// judged on held-out points without rollouts, and their bad settings.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "physics/oscillators.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/hamiltonian_error.h"
#include "tasks/experiments/registry.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

using nlohmann::json;
using testing::TempDir;

const std::vector<std::string> kScattered = {"henon-heiles", "pendulum-scattered",
                                             "double-pendulum-scattered"};

TEST(HamiltonianRelL2, IsZeroForTheTrueHShiftedByAConstant) {
  const Eigen::VectorXd truth = Eigen::VectorXd::LinSpaced(50, 0.5, 3.0);
  EXPECT_LT(hamiltonian_rel_l2(truth, (truth.array() + 17.25).matrix()), 1e-15);
  EXPECT_EQ(hamiltonian_rel_l2(truth, truth), 0.0);
  // Off by e = (+d, -d, ...) with mean 0: ||e|| / ||truth||, the paper's formula.
  Eigen::VectorXd learned = truth;
  for (Eigen::Index i = 0; i < truth.size(); ++i) learned(i) += i % 2 ? -0.1 : 0.1;
  EXPECT_NEAR(hamiltonian_rel_l2(truth, learned), 0.1 * std::sqrt(50.0) / truth.norm(), 1e-14);
  // A scale error is not a constant: it stays.
  EXPECT_GT(hamiltonian_rel_l2(truth, 2 * truth), 0.1);
  EXPECT_TRUE(std::isnan(hamiltonian_rel_l2(Eigen::VectorXd::Zero(3), truth.head(3))));
  EXPECT_TRUE(std::isnan(hamiltonian_rel_l2(truth, truth.head(3))));
}

TEST(HamiltonianRelL2, MetricsSayWhenTheModelHasNoH) {
  const physics::Spring spring;
  Batch x(3, 2);
  x << 0.1, 0.2, -0.3, 0.4, 0.5, -0.6;
  const LearnedField exact{.field = spring.field(),
                           .hamiltonian = [&](const Batch& s) -> Eigen::VectorXd {
                             return spring.hamiltonian_batch(s).array() - 4.0;
                           }};
  const json m = hamiltonian_error_metrics(spring, exact, x);
  EXPECT_LT(m["hamiltonian_rel_l2"].get<double>(), 1e-15);
  EXPECT_EQ(m["hamiltonian_rel_l2_count"], 3);
  const json none = hamiltonian_error_metrics(spring, LearnedField{.field = spring.field()}, x);
  EXPECT_TRUE(none["hamiltonian_rel_l2"].is_null());
  EXPECT_TRUE(none.contains("hamiltonian_rel_l2_note"));
}

TEST(ScatteredTasks, DataAreUniformInThePapersBoxWithExactDerivatives) {
  struct Expected {
    std::string task;
    int train, test;
    double q, p;  // half widths
  };
  for (const Expected& e :
       std::vector<Expected>{{"henon-heiles", 20000, 20000, 5, 5},
                             {"pendulum-scattered", 10000, 10000, 2 * std::numbers::pi, 1},
                             {"double-pendulum-scattered", 20000, 20000, std::numbers::pi, 1}}) {
    const std::unique_ptr<FieldTask> task = make_field_task(e.task);
    EXPECT_TRUE(task->scattered()) << e.task;
    const Dataset d = task->build_dataset(7);
    ASSERT_EQ(d.train_x.rows(), e.train) << e.task;
    ASSERT_EQ(d.test_x.rows(), e.test) << e.task;
    const Eigen::Index n = d.train_x.cols() / 2;
    EXPECT_LE(d.train_x.leftCols(n).cwiseAbs().maxCoeff(), e.q) << e.task;
    EXPECT_GT(d.train_x.leftCols(n).cwiseAbs().maxCoeff(), 0.99 * e.q) << e.task;
    EXPECT_LE(d.test_x.rightCols(n).cwiseAbs().maxCoeff(), e.p) << e.task;
    EXPECT_GT(d.test_x.rightCols(n).cwiseAbs().maxCoeff(), 0.99 * e.p) << e.task;
    Batch field;
    task->truth().vector_field(d.test_x, field);
    EXPECT_EQ(field, d.test_dxdt) << e.task;
    EXPECT_EQ(task->build_dataset(7).train_x, d.train_x) << e.task;  // deterministic
  }
}

// The peer's H: the single pendulum's p^2/2 + 1 - cos q; the double pendulum's potential zero at
// the pivot (H(0) = -3 with unit constants); Hénon-Heiles' alpha from the settings.
TEST(ScatteredTasks, TruthsAreThePapersHamiltonians) {
  Batch x(1, 2);
  x << 0.7, -0.4;
  EXPECT_NEAR(make_field_task("pendulum-scattered")->truth().hamiltonian(x.row(0)),
              0.08 + 1 - std::cos(0.7), 1e-15);
  EXPECT_DOUBLE_EQ(
      make_field_task("double-pendulum-scattered")->truth().hamiltonian(Eigen::RowVector4d::Zero()),
      -3.0);
  const std::unique_ptr<FieldTask> hh = make_field_task("henon-heiles");
  const RunSettings s{.task = "henon-heiles",
                      .task_settings = {{"alpha", 0.0}, {"train_points", 10}, {"test_points", 5}}};
  const Dataset d = hh->build_dataset(s);
  ASSERT_EQ(d.train_x.rows(), 10);
  // alpha 0: two uncoupled unit oscillators, dp/dt = -q.
  EXPECT_LT((d.train_dxdt.rightCols(2) + d.train_x.leftCols(2)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(hh->truth_for(s)->hamiltonian(Eigen::RowVector4d(1, 1, 0, 0)), 1.0, 1e-15);
}

TEST(ScatteredTasks, TrainAFewStepsAndAreJudgedOnHeldOutPointsWithoutRollouts) {
  for (const std::string& name : kScattered) {
    TempDir dir(name);
    RunOptions o = testing::small_run(name, "hnn", dir.path(), 5);
    o.task_settings = {{"train_points", 64}, {"test_points", 32}};
    o.batch_size = 16;
    o.hidden = std::vector<int>{8};
    const json m = run_training(o);
    ASSERT_TRUE(m["hamiltonian_rel_l2"].is_number()) << name << m.dump();
    EXPECT_GT(m["hamiltonian_rel_l2"].get<double>(), 0) << name;
    EXPECT_EQ(m["hamiltonian_rel_l2_count"], 32) << name;
    EXPECT_EQ(m["rollouts_skipped"], kRolloutsSkipped) << name;
    EXPECT_TRUE(m["test_r2"].is_number()) << name;
    for (const char* absent : {"valid_prediction_time", "energy_mse", "rollouts", "state_mse"})
      EXPECT_FALSE(m.contains(absent)) << name << " has " << absent;
    EXPECT_FALSE(std::filesystem::exists(dir / "rollout.csv")) << name;
    // `hnn rollout` on request, from test points over a span short enough for Hénon-Heiles'
    // box, whose states mostly escape its well.
    EXPECT_EQ(write_rollout(dir.path(), RolloutCommand{}).trajectories, 5) << name;
    EXPECT_EQ(testing::read_json(dir / "metrics.json")["hamiltonian_rel_l2"],
              m["hamiltonian_rel_l2"])
        << name;
  }
  // A baseline learns no H: the key is null and a note says why.
  TempDir dir("baseline");
  RunOptions o = testing::small_run("pendulum-scattered", "baseline", dir.path(), 3);
  o.task_settings = {{"train_points", 40}, {"test_points", 10}};
  o.batch_size = 20;
  o.hidden = std::vector<int>{8};
  const json m = run_training(o);
  EXPECT_TRUE(m["hamiltonian_rel_l2"].is_null());
  EXPECT_TRUE(m.contains("hamiltonian_rel_l2_note"));
}

// Tasks with rollouts gain the metric beside their others.
TEST(ScatteredTasks, TheMetricIsOnEveryFieldTaskWithATrueH) {
  TempDir dir("spring");
  const json m = run_training(testing::small_run("spring", "hnn", dir.path(), 5));
  ASSERT_TRUE(m["hamiltonian_rel_l2"].is_number());
  EXPECT_EQ(m["hamiltonian_rel_l2_count"], m["n_test"]);
  EXPECT_TRUE(m.contains("valid_prediction_time"));
  EXPECT_FALSE(m.contains("rollouts_skipped"));
}

std::string scattered_settings_error(const std::string& task, const json& settings) {
  try {
    const std::unique_ptr<FieldTask> t = make_field_task(task);
    t->check_task_settings(settings);
    t->build_dataset(RunSettings{.task = task, .task_settings = settings});
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ScatteredTasks, BadSettingsAreRefusedByName) {
  EXPECT_EQ(scattered_settings_error("henon-heiles", {{"train_points", 1}}),
            "henon-heiles: train_points must be an integer from 2 to 10000000, got 1");
  EXPECT_EQ(scattered_settings_error("pendulum-scattered", {{"test_points", 2.5}}),
            "pendulum-scattered: test_points must be an integer from 1 to 10000000, got 2.5");
  EXPECT_EQ(scattered_settings_error("double-pendulum-scattered", {{"q_range", {1, -1}}}),
            "double-pendulum-scattered: q_range must be [LO, HI] with finite LO < HI, got [1,-1]");
  EXPECT_EQ(scattered_settings_error("henon-heiles", {{"p_range", "wide"}}),
            "henon-heiles: p_range must be [LO, HI] with finite LO < HI, got \"wide\"");
  EXPECT_EQ(scattered_settings_error("henon-heiles", {{"alpha", -1}}),
            "henon-heiles: alpha must be a finite number >= 0, got -1");
  // No rollouts: their settings are not the tasks'; alpha is Hénon-Heiles' alone.
  EXPECT_TRUE(scattered_settings_error("henon-heiles", {{"rollouts", 5}})
                  .starts_with("task 'henon-heiles' has no setting 'rollouts' (known: "));
  EXPECT_TRUE(scattered_settings_error("pendulum-scattered", {{"alpha", 1}})
                  .starts_with("task 'pendulum-scattered' has no setting 'alpha'"));
  EXPECT_EQ(scattered_settings_error("henon-heiles", {{"alpha", 0.5}, {"q_range", {-1, 1}}}), "");
}

TEST(ScatteredTasks, TheRolloutLossIsRefused) {
  TempDir dir("rollout-loss");
  RunOptions o = testing::small_run("henon-heiles", "hnn", dir.path(), 2);
  o.task_settings = {{"train_points", 20}, {"test_points", 5}, {"loss", "rollout"}};
  o.batch_size = 10;
  try {
    run_training(o);
    FAIL() << "the rollout loss was accepted on scattered states";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the rollout loss needs trajectories"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hnn::tasks
