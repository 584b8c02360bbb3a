// The real double pendulum (measured, Schmidt & Lipson): its data are the file's angles,
// velocities and derivative columns split in time per trial; short lnn and baseline runs train
// in seconds and are judged along the measured held-out trajectories; models that need momenta
// are refused, and an lnn on a task without velocities gets one line saying why.

#include <gtest/gtest.h>

#include <cmath>

#include "physics/lipson.h"
#include "tasks/data/data_files.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

using nlohmann::json;
using testing::TempDir;

TEST(RealDoublePendulum, TrainsOnTheFilesDerivativesSplitInTimePerTrial) {
  const Dataset d = build_dataset("real-double-pendulum", 0);
  ASSERT_EQ(d.train_x.cols(), 4);
  EXPECT_EQ(d.train_x.rows() + d.test_x.rows(), 1520);  // every row of both trials
  EXPECT_NEAR(double(d.test_x.rows()) / 1520, 0.2, 0.01);
  // dq/dt is the file's velocity, dw/dt its acceleration column.
  EXPECT_EQ(d.train_dxdt.leftCols(2), d.train_x.rightCols(2));
  const physics::LipsonData file =
      physics::load_lipson(default_data_path("lipson/real_double_pend_h_1.txt"));
  EXPECT_EQ(d.train_x.row(0), file.state().row(0));
  // The test set holds the end of both trials (trial 1 is the one with angles below -10).
  EXPECT_LT(d.test_x.col(1).minCoeff(), -10);
  EXPECT_GT(d.test_x.col(1).maxCoeff(), -10);
}

TEST(RealDoublePendulum, ShortLnnAndBaselineRunsLearnAndFollowTheMeasurements) {
  TempDir dir("runs");
  std::map<std::string, json> m;
  for (const auto& [model, steps] : {std::pair{"baseline", 300}, std::pair{"lnn", 150}}) {
    RunOptions o = testing::small_run("real-double-pendulum", model, dir / model, steps);
    o.task_settings = {{"rollouts", 8}};
    m[model] = run_training(o);
  }
  // The baseline beats the constant predictor (the test targets' mean) on the test field.
  EXPECT_GT(m["baseline"]["test_r2"].get<double>(), 0) << m["baseline"].dump();
  for (const char* model : {"baseline", "lnn"}) {
    const json& r = m[model];
    EXPECT_TRUE(std::isfinite(r["test_loss"].get<double>())) << model;
    EXPECT_GT(r["test_loss_se"].get<double>(), 0) << model;
    EXPECT_EQ(r["rollouts"], 8) << model;
    EXPECT_TRUE(r["energy_mse"].is_null()) << model;  // no true system
    EXPECT_TRUE(r["relative_error_floor"].is_null()) << model;
    const int n = r["n_rollouts"];
    EXPECT_EQ(n + int(r["rollout_failures"].size()), 8) << model;
    if (n == 0) continue;
    for (const char* key :
         {"state_mse_t0.05", "state_mse_t0.5", "relative_error_geomean", "valid_prediction_time"}) {
      EXPECT_TRUE(r[key].is_number()) << model << " " << key;
      EXPECT_TRUE(r[std::string(key) + "_se"].is_number()) << model << " " << key;
    }
    EXPECT_GT(r["state_mse_t0.05_count"].get<int>(), 0) << model;
  }
  // `hnn rollout` writes the measured paths beside the model's.
  const LoadedRun run = load_run(dir / "baseline");
  const RolloutOutput out = run.run->rollout({.points = 11, .trajectories = 2});
  EXPECT_EQ(out.trajectories, 2);
  const std::string& csv = out.csv;
  EXPECT_NE(csv.find("\ndata,0,0,"), std::string::npos) << csv.substr(0, 200);
  EXPECT_NE(csv.find("\nbaseline,1,"), std::string::npos);
  // Past the measured paths (1 s) the truth is unavailable, and the note says so; from a given
  // state there is none at all.
  const RolloutOutput longer = run.run->rollout({.t_end = 3, .points = 11, .trajectories = 1});
  ASSERT_EQ(longer.notes.size(), 1u);
  EXPECT_EQ(longer.notes[0],
            "real-double-pendulum: the truth is unavailable past the data: the measured paths end "
            "at t = 1 and the model's run to t = 3");
  const RolloutOutput given =
      run.run->rollout({.points = 3, .initial_states = Eigen::RowVector4d(0.1, 0.2, 0, 0)});
  EXPECT_EQ(given.trajectories, 1);
  EXPECT_EQ(given.csv.find("\ndata,"), std::string::npos);
  ASSERT_EQ(given.notes.size(), 1u);
}

TEST(RealDoublePendulum, RefusesModelsThatNeedMomenta) {
  TempDir dir("runs");
  for (const char* model : {"hnn", "dhnn"}) {
    RunOptions o = testing::small_run("real-double-pendulum", model, dir / model, 5);
    try {
      run_training(o);
      FAIL() << model << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()),
                fmt::format("task 'real-double-pendulum' does not train a {} model (its models: "
                            "lnn, baseline)",
                            model));
    }
    EXPECT_FALSE(std::filesystem::exists(dir / model));
  }
}

TEST(LnnOnATaskWithoutVelocities, GetsOneLineSayingWhyAndWhere) {
  TempDir dir("runs");
  for (const char* task : {"spring", "two-body", "real-pendulum"}) {
    RunOptions o = testing::small_run(task, "lnn", dir / task, 5);
    try {
      run_training(o);
      FAIL() << task << " accepted an lnn";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find(fmt::format("task '{}' does not train a lnn model", task)),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("from coordinates and their velocities, which this task's states are "
                          "not (tasks that have them: double-pendulum, real-double-pendulum, "
                          "chain-pendulum-2, chain-pendulum-3, chain-pendulum-4, chain-pendulum-5, "
                          "coupled-pendulums, magnet-pendulum, gyroscope, rotor)"),
                std::string::npos)
          << what;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / task));
  }
  // Finzi et al.'s HNN learns its mass matrix from velocities too: the chains' angle twins and
  // the other constrained systems' body coordinates.
  try {
    run_training(testing::small_run("spring", "hnn-mass", dir / "mass", 5));
    FAIL() << "spring accepted an hnn-mass";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "an hnn-mass learns from coordinates and their velocities, which this task's "
                  "states are not (tasks that have them: chain-pendulum-2, chain-pendulum-3, "
                  "chain-pendulum-4, chain-pendulum-5, coupled-pendulums, magnet-pendulum, "
                  "gyroscope, rotor)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hnn::tasks
