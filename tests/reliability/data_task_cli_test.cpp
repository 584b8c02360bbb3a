// `hnn train data`: a short run from a simulated CSV through the program, and every bad option
// of the data task: one line "hnn: error: ...", exit 1, no run folder (docs/inputs.md).

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

TEST(DataTaskCli, TrainsOnASimulatedFileAndRefusesBadOptionsInOneLine) {
  const TempDir dir;
  const std::string csv = simulated_pendulum_csv(dir.path()), out = (dir / "run").string();
  const std::vector<std::string> base = {"train",    "data",      "--data",  csv,       "--coords",
                                         "q",        "--momenta", "p",       "--steps", "30",
                                         "--hidden", "8",         "--quiet", "--out",   out};
  const Result good = run_hnn(base, dir.path());
  ASSERT_EQ(good.code, 0) << good.err;
  // simulate's exact dx/dt columns, found by their names, and said so.
  EXPECT_NE(
      good.err.find("hnn: data: " + csv + ": dx/dt from the columns dq/dt, dp/dt, found by name"),
      std::string::npos)
      << good.err;
  const nlohmann::json m = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(m["task_settings"], nlohmann::json({{"coords", {"q"}}, {"momenta", {"p"}}}));
  EXPECT_TRUE(fs::exists(dir / "run" / "rollout.csv"));
  fs::remove_all(dir / "run");

  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const std::vector<BadTrain> cases = {
      {{"train", "spring", "--coords", "q", "--out", out},
       "--coords applies to the data task only, not to 'spring'\n"},
      {{"train", "data", "--out", out}, "the data task needs a file: hnn train data --data FILE"},
      {with({"--hamiltonian", "p^2 + k*q^2"}),
       "--hamiltonian: hamiltonian 'p^2 + k*q^2': unknown name 'k'"},
      {with({"--split", "random"}), "--split: random not in {auto,trajectories,time}"},
      {with({"--test-fraction", "1"}), "test fraction 1 is not between 0 and 1\n"},
      {with({"--split", "time", "--coords", "x"}), csv + ": no column 'x' (columns: trajectory, "},
      {with({"--derivatives", "dq/dt"}),
       csv + ": 1 derivative columns (dq/dt) for a state of 2: give dx/dt of every coordinate, "},
      {with({"--settings", "{\"colour\": 1}"}), "the data task has no setting 'colour' (known: "},
  };
  for (const BadTrain& bad : cases) {
    const Result r = run_hnn(bad.args, dir.path());
    const std::string what = fmt::format("{}", fmt::join(bad.args, " "));
    expect_one_line_error_starting(r, bad.message, what);
    EXPECT_FALSE(fs::exists(dir / "run")) << what;
  }
}

}  // namespace
}  // namespace hnn::reliability
