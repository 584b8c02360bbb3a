// `hnn evaluate RUN --against OTHER`: two runs of one task and the same data side by side, with
// the ratios OTHER / RUN of their metrics.json's figures; runs of other tasks or other data are
// refused in one line (docs/inputs.md).

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

// The line of `text` that starts with `start` (after its indent), or "".
std::string line_starting(const std::string& text, const std::string& start) {
  for (const std::string& line : lines(text))
    if (line.find_first_not_of(' ') != std::string::npos &&
        line.substr(line.find_first_not_of(' ')).starts_with(start))
      return line;
  return "";
}

Result train(const TempDir& dir, const std::string& task, const std::string& model,
             const std::string& seed) {
  return run_hnn({"train", task, "--model", model, "--seed", seed, "--steps", "5", "--hidden", "8",
                  "--quiet", "--out", (dir / (task + "_" + model + "_" + seed)).string()},
                 dir.path());
}

TEST(EvaluateAgainst, ShowsTwoRunsOfTheSameDataSideBySideWithTheirRatios) {
  const TempDir dir;
  for (const char* model : {"hnn", "baseline"}) ASSERT_EQ(train(dir, "spring", model, "0").code, 0);
  ASSERT_EQ(train(dir, "spring", "hnn", "1").code, 0);
  ASSERT_EQ(train(dir, "pendulum", "baseline", "0").code, 0);
  const fs::path hnn = dir / "spring_hnn_0", baseline = dir / "spring_baseline_0";
  const Result r = run_hnn({"evaluate", hnn.string(), "--against", baseline.string()}, dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json a = read_json(hnn / "metrics.json"),
                       b = read_json(baseline / "metrics.json");
  EXPECT_NE(line_starting(r.out, "against    " + baseline.string()), "") << r.out;
  EXPECT_NE(r.out.find(" baseline / hnn\n"), std::string::npos) << r.out;  // the heading
  for (const auto& [label, key] :
       {std::pair{"energy MSE ", "energy_mse"}, std::pair{"test loss ", "test_loss"},
        std::pair{"valid prediction time ", "valid_prediction_time"}}) {
    const std::string line = line_starting(r.out, label);
    const std::string ratio = fmt::format(" {:.3g}", b[key].get<double>() / a[key].get<double>());
    EXPECT_TRUE(line.ends_with(ratio)) << label << ": " << line << " (expected" << ratio << ")";
  }
  EXPECT_NE(line_starting(r.out, "test R²"), "") << r.out;

  // --json: both runs' metrics.
  const Result json =
      run_hnn({"evaluate", hnn.string(), "--against", baseline.string(), "--json"}, dir.path());
  ASSERT_EQ(json.code, 0) << json.err;
  const nlohmann::json both = nlohmann::json::parse(json.out);
  EXPECT_EQ(both["against"]["energy_mse"], b["energy_mse"]);
  EXPECT_EQ(both["run"]["energy_mse"], a["energy_mse"]);

  for (const auto& [other, message] :
       {std::pair{dir / "spring_hnn_1", "runs of other data (seed: 0 against 1)"},
        std::pair{dir / "pendulum_baseline_0",
                  "runs of other tasks (task: \"spring\" against \"pendulum\")"}}) {
    const Result refused =
        run_hnn({"evaluate", hnn.string(), "--against", other.string()}, dir.path());
    EXPECT_EQ(refused.code, 1);
    EXPECT_EQ(refused.out, "");
    EXPECT_EQ(lines(refused.err).size(), 1u) << refused.err;
    EXPECT_EQ(refused.err, fmt::format("hnn: error: --against {}: not comparable with {}: {}\n",
                                       other.string(), hnn.string(), message));
  }
}

}  // namespace
}  // namespace hnn::reliability
