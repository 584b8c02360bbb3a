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

}  // namespace
}  // namespace hnn::reliability
