// `hnn train TASK --loss rollout`: a short run through the program records how it trained, and
// every bad setting of the rollout loss is one line "hnn: error: ...", exit 1, no run folder
// (docs/inputs.md).

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

TEST(RolloutCli, TrainsThroughLeapfrogAndRefusesBadSettingsInOneLine) {
  const TempDir dir;
  const std::string out = (dir / "run").string();
  const Result good =
      run_hnn({"train", "spring", "--loss", "rollout", "--integrator", "leapfrog", "--horizon", "2",
               "--dt", "0.5", "--settings", "{\"sample_dt\": 1.0}", "--steps", "20", "--hidden",
               "8", "--quiet", "--out", out},
              dir.path());
  ASSERT_EQ(good.code, 0) << good.err;
  const nlohmann::json m = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(m["training"],
            nlohmann::json(
                {{"loss", "rollout"}, {"integrator", "leapfrog"}, {"horizon", 2}, {"dt", 0.5}}));
  EXPECT_EQ(m["task_settings"]["integrator"], "leapfrog");
  EXPECT_EQ(m["stretch_predictor"], "leapfrog, 2 step(s) per interval");
  fs::remove_all(dir / "run");

  const std::vector<BadTrain> cases = {
      {{"train", "spring", "--horizon", "3"},
       "spring: --horizon, --integrator, --dt, --norm and --minibatches apply to the rollout loss "
       "only (add --loss rollout)\n"},
      {{"train", "pendulum", "--integrator", "midpoint"},
       "pendulum: --horizon, --integrator, --dt, --norm and --minibatches apply to the rollout"},
      {{"train", "two-body", "--dt", "0.1"},
       "two-body: --horizon, --integrator, --dt, --norm and --minibatches apply to the rollout"},
      {{"train", "spring", "--minibatches", "epochs"},
       "spring: --horizon, --integrator, --dt, --norm and --minibatches apply to the rollout"},
      {{"train", "spring", "--loss", "rollout", "--minibatches", "sometimes"},
       "--minibatches: sometimes not in {independent,epochs}"},
      {{"train", "spring", "--loss", "rollout", "--horizon", "30"},
       "a horizon of 30 steps is past the end of every training stretch (the longest has 30 "
       "points, so 29 steps at most)\n"},
      {{"train", "spring", "--loss", "rollout", "--settings", "{\"sample_dt\": 0.5}", "--dt",
        "0.3"},
       "--dt 0.3 does not divide the sampling interval (0.5) into whole steps: use the interval "
       "divided by a whole number\n"},
      {{"train", "spring", "--loss", "rollout", "--integrator", "euler"},
       "--integrator: euler not in {leapfrog,yoshida4,midpoint,rk4,rk4-38}"},
      {{"train", "spring", "--loss", "sideways"}, "--loss: sideways not in {derivative,rollout}"},
      {{"train", "damped-spring", "--loss", "rollout"},
       "damped-spring: the rollout loss needs trajectories, and this task's data are states "
       "without them (use --loss derivative)\n"},
      {{"train", "spring", "--settings", "{\"sample_dt\": 0.7}"},
       "spring: sample_dt 0.7 does not divide t_end 3 into whole intervals\n"},
      {{"train", "three-body", "--settings", "{\"setup\": \"hnn\"}"},
       "three-body: setup \"hnn\" is not one of: srnn (three-body only)\n"},
      {{"train", "pixel-pendulum", "--loss", "rollout"},
       "pixel-pendulum has no setting 'loss' (known: "},
  };
  for (const BadTrain& bad : cases) {
    std::vector<std::string> args = bad.args;
    args.insert(args.end(), {"--steps", "5", "--hidden", "8", "--quiet", "--out", out});
    const Result r = run_hnn(args, dir.path());
    const std::string what = fmt::format("{}", fmt::join(bad.args, " "));
    expect_one_line_error_starting(r, bad.message, what);
    EXPECT_FALSE(fs::exists(dir / "run")) << what;
  }
}

}  // namespace
}  // namespace hnn::reliability
