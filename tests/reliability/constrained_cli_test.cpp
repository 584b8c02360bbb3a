// The constrained systems' tasks through the program: a run prints Finzi et al.'s error, its
// floor and the failed rollouts beside it and writes them to metrics.json; the refusals (an angle
// model on a system without angles, the L1 norm without the rollout loss) are one line
// "hnn: error: ...", exit 1, nothing written.

#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

std::vector<std::string> tiny_train(const std::string& task, const std::string& model,
                                    const fs::path& out) {
  return {"train",   task,         "--model",
          model,     "--steps",    "2",
          "--batch", "4",          "--hidden",
          "8",       "--settings", R"({"trajectories": 6, "validation": 2, "rollouts": 2})",
          "--out",   out.string()};
}

TEST(ConstrainedCli, ARunReportsTheErrorItsFloorAndTheFailedRollouts) {
  const TempDir dir;
  const Result r = run_hnn(tiny_train("chain-pendulum-2", "baseline", dir / "run"), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("Cartesian relative error"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("floor"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" of 2\n"), std::string::npos) << r.out;  // failed rollouts k of 2
  const nlohmann::json m = read_json(dir / "run" / "metrics.json");
  for (const char* key : {"cartesian_error", "cartesian_error_floor", "cartesian_error_failed"})
    EXPECT_TRUE(m.contains(key)) << key;
}

TEST(ConstrainedCli, RefusesAngleModelsWithoutAnglesAndL1WithoutTheRolloutLoss) {
  const TempDir dir;
  Result r = run_hnn(tiny_train("gyroscope", "hnn", dir / "hnn"), dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("angle coordinates"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "hnn"));
  std::vector<std::string> args = tiny_train("chain-pendulum-2", "baseline", dir / "l1");
  for (const char* extra : {"--loss", "derivative", "--norm", "l1"}) args.push_back(extra);
  r = run_hnn(args, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("apply to the rollout loss only"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "l1"));
}

// `hnn rollout` from your own states: a Cartesian state off the rods would make the truth a
// system with other rods, so it is refused in one line naming the state and the rod; --project
// moves it onto them and says how far; --project is refused where there is nothing to move.
TEST(ConstrainedCli, RolloutRefusesAStateOffTheRodsOrProjectsIt) {
  const TempDir dir;
  ASSERT_EQ(run_hnn(tiny_train("chain-pendulum-2", "baseline", dir / "run"), dir.path()).code, 0);
  // Point 0 at (0.5, -0.5), point 1 at (1, -1): 0.707 apart, where the rods are 1.036 and 1.082.
  const std::vector<std::string> off = {
      "rollout", (dir / "run").string(),    "--state", "0.5,-0.5,1,-1,0,0,0,0", "--t-end", "0.3",
      "--out",   (dir / "off.csv").string()};
  Result r = run_hnn(off, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err,
            "hnn: error: given state 1 is off chain-pendulum-2's constraints: points 0 and 1 are "
            "0.707107 apart, their rod is 1.08221 long; --project moves given states onto them\n");
  EXPECT_FALSE(fs::exists(dir / "off.csv"));

  std::vector<std::string> projected = off;
  projected.push_back("--project");
  r = run_hnn(projected, dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("moved 1 given state onto chain-pendulum-2's constraints, the furthest by"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(dir / "off.csv"));

  r = run_hnn({"rollout", (dir / "run").string(), "--project"}, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("the run's own test states are on them"), std::string::npos) << r.err;

  ASSERT_EQ(run_hnn({"train", "spring", "--steps", "2", "--hidden", "8", "--out",
                     (dir / "spring").string(), "--quiet"},
                    dir.path())
                .code,
            0);
  r = run_hnn({"rollout", (dir / "spring").string(), "--state", "1,0", "--project"}, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("spring's states have none"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hnn::reliability
