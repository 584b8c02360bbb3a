// docs/inputs.md, "Training checkpoints": `hnn train --resume RUN --steps N` continues a finished
// run to N steps and ends as a run of N steps from the start, bit for bit (constant learning
// rate: Adam's moments and step count, and the minibatch generator, are in the checkpoint);
// metrics.json records the steps it was continued from. What cannot end so is refused.

#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

std::vector<std::string> minibatch_spring(const fs::path& out, const std::string& steps,
                                          const std::string& schedule = "constant") {
  return {"train",         "spring", "--steps", steps,   "--hidden",  "8",
          "--batch",       "25",     "--lr",    "0.01",  "--seed",    "2",
          "--lr-schedule", schedule, "--quiet", "--out", out.string()};
}

Result continue_to(const fs::path& run, const std::string& steps, const fs::path& dir) {
  return run_hnn({"train", "--resume", run.string(), "--steps", steps, "--quiet"}, dir);
}

TEST(ContinueRun, AFinishedRunContinuedEqualsOneTrainedForAllItsStepsBitForBit) {
  const TempDir dir;
  const fs::path whole = dir / "whole", run = dir / "run";
  ASSERT_EQ(run_hnn(minibatch_spring(whole, "40"), dir.path()).code, 0);
  ASSERT_EQ(run_hnn(minibatch_spring(run, "15"), dir.path()).code, 0);
  const Result continued = continue_to(run, "40", dir.path());
  ASSERT_EQ(continued.code, 0) << continued.err;
  EXPECT_EQ(read_text(run / "params.bin"), read_text(whole / "params.bin"));
  // Both curves have a point every step (fewer than 200 steps): the same points.
  EXPECT_EQ(read_text(run / "loss_curve.csv"), read_text(whole / "loss_curve.csv"));
  EXPECT_EQ(read_text(run / "rollout.csv"), read_text(whole / "rollout.csv"));
  nlohmann::json m = without_timings(read_json(run / "metrics.json"));
  EXPECT_EQ(m["continued_from"], nlohmann::json::array({15}));
  m.erase("continued_from");
  const nlohmann::json w = without_timings(read_json(whole / "metrics.json"));
  EXPECT_FALSE(w.contains("continued_from"));
  EXPECT_EQ(m, w);
  // Continued again: both step counts recorded.
  ASSERT_EQ(continue_to(run, "45", dir.path()).code, 0);
  EXPECT_EQ(read_json(run / "metrics.json")["continued_from"], nlohmann::json::array({15, 40}));
  EXPECT_EQ(read_json(run / "metrics.json")["steps"], 45);
}

TEST(ContinueRun, FewerStepsACosineScheduleAndAnUnfinishedRunAreRefused) {
  const TempDir dir;
  const fs::path run = dir / "run", cosine = dir / "cosine";
  ASSERT_EQ(run_hnn(minibatch_spring(run, "15"), dir.path()).code, 0);
  ASSERT_EQ(run_hnn(minibatch_spring(cosine, "15", "cosine"), dir.path()).code, 0);
  const std::string params = read_text(run / "params.bin");
  const auto refused = [&](const fs::path& folder, const std::string& steps,
                           const std::string& message) {
    const Result r = continue_to(folder, steps, dir.path());
    EXPECT_EQ(r.code, 1) << message;
    EXPECT_EQ(r.err, "hnn: error: " + message + "\n");
  };
  refused(run, "10",
          fmt::format("--steps 10 is fewer than the 15 steps run '{}' was trained for: --resume "
                      "with --steps continues a run to more steps",
                      run.string()));
  refused(cosine, "30",
          fmt::format("run '{}' decayed its learning rate to 0 over its 15 steps (--lr-schedule "
                      "cosine): continuing it would start the decay again; train a new run with "
                      "--steps 30",
                      cosine.string()));
  // An unfinished run (its checkpoint says step 10 of 15) is resumed first, then continued.
  nlohmann::json state = read_json(run / "checkpoint" / "state.json");
  state["step"] = 10;
  write_text(run / "checkpoint" / "state.json", state.dump());
  refused(run, "30",
          fmt::format("'{0}' holds an unfinished run (step 10 of 15): --steps continues a finished "
                      "run; finish this one first with `hnn train --resume {0}`",
                      run.string()));
  EXPECT_EQ(read_text(run / "params.bin"), params);
}

}  // namespace
}  // namespace hnn::reliability
