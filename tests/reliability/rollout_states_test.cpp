// `hnn rollout` from a user's own initial states (--state, --states FILE) over any horizon, with
// the truth wherever the run knows H and a plain note where it does not, and the count it
// prints being the count it wrote; every bad input one line "hnn: error: ...", exit 1, no CSV
// (docs/inputs.md).

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

// The rows of `csv` (the lines after its header) whose source is `source`, split at commas.
std::vector<std::vector<std::string>> rows_of(const fs::path& csv, const std::string& source) {
  std::vector<std::vector<std::string>> rows;
  const std::vector<std::string> all = lines(read_text(csv));
  for (std::size_t i = 1; i < all.size(); ++i) {
    if (!all[i].starts_with(source + ",")) continue;
    std::vector<std::string> cells(1);
    for (char c : all[i]) {
      if (c == ',') {
        cells.emplace_back();
      } else {
        cells.back().push_back(c);
      }
    }
    rows.push_back(cells);
  }
  return rows;
}

struct Bad {
  std::vector<std::string> extra;
  std::string message;
};

// Each bad input: exit 1, one line starting with "hnn: error: " + message, no CSV written.
void expect_refused(const fs::path& run, const fs::path& dir, const std::vector<Bad>& cases) {
  for (const Bad& bad : cases) {
    std::vector<std::string> args = {"rollout", run.string(), "--out", (dir / "bad.csv").string()};
    args.insert(args.end(), bad.extra.begin(), bad.extra.end());
    const Result r = run_hnn(args, dir);
    const std::string what = fmt::format("{}", fmt::join(bad.extra, " "));
    expect_one_line_error_starting(r, bad.message, what);
    EXPECT_FALSE(fs::exists(dir / "bad.csv")) << what;
  }
}

TEST(RolloutStates, ABuiltInSystemRollsOutFromGivenStatesWithItsTruth) {
  const TempDir dir;
  const fs::path run = dir / "run", out = dir / "mine.csv";
  ASSERT_EQ(run_hnn({"train", "spring", "--steps", "5", "--hidden", "8", "--quiet", "--out",
                     run.string()},
                    dir.path())
                .code,
            0);
  const Result r = run_hnn({"rollout", run.string(), "--state", "0.5,0", "--state=-1, 0.25",
                            "--t-end", "2", "--points", "5", "--out", out.string()},
                           dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("hnn rollout: 2 trajectories, dopri5 -> "), std::string::npos) << r.out;
  EXPECT_EQ(lines(read_text(out))[0], "source,traj,t,x_0,x_1,energy,learned_h");
  for (const char* source : {"true", "hnn"}) {
    const auto rows = rows_of(out, source);
    ASSERT_EQ(rows.size(), 2u * 5u) << source;
    EXPECT_EQ(std::vector<std::string>(rows[0].begin() + 1, rows[0].begin() + 5),
              std::vector<std::string>({"0", "0", "0.5", "0"}))
        << source;
    EXPECT_EQ(std::vector<std::string>(rows[5].begin() + 1, rows[5].begin() + 5),
              std::vector<std::string>({"1", "0", "-1", "0.25"}))
        << source;
    EXPECT_EQ(rows[9][2], "2") << source;  // the whole horizon, the truth too
  }

  // A file: its header names the columns, in any order.
  write_text(dir / "states.csv", "x_1,x_0\n0.25,-1\n");
  ASSERT_EQ(run_hnn({"rollout", run.string(), "--states", (dir / "states.csv").string(), "--points",
                     "3", "--out", out.string()},
                    dir.path())
                .code,
            0);
  EXPECT_EQ(rows_of(out, "true").at(0).at(3), "-1");
  EXPECT_EQ(rows_of(out, "true").at(0).at(4), "0.25");

  const std::string file = (dir / "bad_states.csv").string();
  write_text(dir / "bad_states.csv", "x_0,y\n1,2\n");
  expect_refused(run, dir.path(),
                 {{{"--state", "1,2,3"}, "--state '1,2,3': 3 numbers, and a state has 2: x_0, x_1"},
                  {{"--state", "1,abc"}, "--state '1,abc': value 2 (x_1): 'abc' is not a number"},
                  {{"--states", file},
                   file + ": header: column 'y' is not a state column; the "
                          "run's are x_0, x_1"},
                  {{"--state", "1,2", "--trajectories", "2"}, "--trajectories excludes --state"}});
  write_text(dir / "bad_states.csv", "x_0,x_1\n1,2\n3,zz\n");
  write_text(dir / "short.csv", "x_0\n1\n");
  expect_refused(run, dir.path(),
                 {{{"--states", file}, file + ":3: column 'x_1': 'zz' is not a number"},
                  {{"--states", (dir / "short.csv").string()},
                   (dir / "short.csv").string() + ": header: no column 'x_1'"}});
}

// A data run: its own column names and units; the truth past the data only with an H.
class RolloutOfDataRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("RolloutOfDataRun");
    ASSERT_EQ(run_hnn({"simulate", "--hamiltonian", "p^2/2 + 2*(1 - cos(q))", "--coords", "q",
                       "--momenta", "p", "--trajectories", "10", "--t-end", "2", "--points", "15",
                       "--out", (*dir_ / "pend.csv").string()},
                      dir_->path())
                  .code,
              0);
    for (const bool with_h : {false, true}) {
      std::vector<std::string> args = {"train",
                                       "data",
                                       "--data",
                                       (*dir_ / "pend.csv").string(),
                                       "--coords",
                                       "q",
                                       "--momenta",
                                       "p",
                                       "--steps",
                                       "20",
                                       "--hidden",
                                       "8",
                                       "--quiet",
                                       "--out",
                                       run(with_h).string()};
      if (with_h) args.insert(args.end(), {"--hamiltonian", "p^2/2 + 2*(1 - cos(q))"});
      ASSERT_EQ(run_hnn(args, dir_->path()).code, 0);
    }
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path run(bool with_h) { return *dir_ / (with_h ? "with_h" : "no_h"); }

  static Result rollout(bool with_h, std::vector<std::string> extra) {
    std::vector<std::string> args = {"rollout", run(with_h).string(), "--out",
                                     (*dir_ / "out.csv").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_hnn(args, dir_->path());
  }
  static fs::path out() { return *dir_ / "out.csv"; }

  static TempDir* dir_;
};
TempDir* RolloutOfDataRun::dir_ = nullptr;

TEST_F(RolloutOfDataRun, WithoutHTheTruthStopsWhereTheDataEndAndSaysSo) {
  const Result r = rollout(false, {"--t-end", "5", "--points", "11"});
  ASSERT_EQ(r.code, 0) << r.err;
  // 10 trajectories, 20% held out: 2 stretches, the default 5 cut to them, and said so.
  EXPECT_NE(r.out.find("hnn rollout: 2 trajectories"), std::string::npos) << r.out;
  EXPECT_EQ(r.err,
            "hnn rollout: data: the truth is unavailable past the data: the shortest held-out "
            "stretch ends at t = 2 and the paths run to t = 5; train with --hamiltonian EXPR to "
            "integrate a known H\n");
  EXPECT_EQ(lines(read_text(out()))[0], "source,traj,t,q,p,energy,learned_h");
  EXPECT_TRUE(rows_of(out(), "true").empty());
  const auto data = rows_of(out(), "data");
  ASSERT_FALSE(data.empty());
  EXPECT_EQ(data.back()[2], "2");  // the data's own end, no padding beyond
  EXPECT_EQ(rows_of(out(), "hnn").back()[2], "5");

  // Given states: no truth at all, and said so; the columns named as the data's, in any order.
  write_text(*dir_ / "states.csv", "p,q\n0.5,1\n");
  const Result given = rollout(false, {"--states", (*dir_ / "states.csv").string()});
  ASSERT_EQ(given.code, 0) << given.err;
  EXPECT_EQ(given.err,
            "hnn rollout: data: the truth is unavailable from your states: the run has no H "
            "(train with --hamiltonian EXPR to integrate one)\n");
  const auto hnn = rows_of(out(), "hnn");
  ASSERT_EQ(hnn.size(), 200u);
  EXPECT_EQ(hnn[0][3], "1");
  EXPECT_EQ(hnn[0][4], "0.5");
  EXPECT_TRUE(rows_of(out(), "data").empty());

  // The count printed is the count written: more than the run has is refused.
  expect_refused(run(false), dir_->path(),
                 {{{"--trajectories", "10"},
                   "--trajectories 10 is more than the 2 held-out stretches this run can start "
                   "from: give at most 2, or your own initial states with --state or --states "
                   "FILE\n"},
                  {{"--state", "1"}, "--state '1': 1 numbers, and a state has 2: q, p"}});
}

TEST_F(RolloutOfDataRun, WithHTheTruthRunsOverTheWholeHorizon) {
  const Result r = rollout(true, {"--t-end", "5", "--points", "11", "--trajectories", "2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto truth = rows_of(out(), "true");
  ASSERT_EQ(truth.size(), 2u * 11u);
  EXPECT_EQ(truth[10][2], "5");
  EXPECT_FALSE(truth[10][5].empty());  // its energy
  // From the held-out stretch's first state, as the data.
  EXPECT_EQ(truth[0][3], rows_of(out(), "data").at(0).at(3));

  const Result given = rollout(true, {"--state", "1,0.5", "--t-end", "5"});
  ASSERT_EQ(given.code, 0) << given.err;
  EXPECT_EQ(rows_of(out(), "true").size(), 200u);
  EXPECT_EQ(rows_of(out(), "true").back()[2], "5");
}

// The run's data moved away (metrics.json names a file that is gone): --data finds them.
TEST_F(RolloutOfDataRun, ADataFileThatMovedIsFoundWithData) {
  const fs::path run = *dir_ / "moved_run";
  fs::copy(RolloutOfDataRun::run(false), run, fs::copy_options::recursive);
  nlohmann::json metrics = read_json(run / "metrics.json");
  metrics["data_file"] = (*dir_ / "gone.csv").string();
  write_text(run / "metrics.json", metrics.dump(2));
  const std::vector<std::string> args = {"rollout", run.string(), "--points",
                                         "3",       "--out",      (*dir_ / "moved.csv").string()};
  EXPECT_EQ(run_hnn(args, dir_->path()).code, 1);
  std::vector<std::string> with_data = args;
  with_data.insert(with_data.end(), {"--data", (*dir_ / "pend.csv").string()});
  const Result r = run_hnn(with_data, dir_->path());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(rows_of(*dir_ / "moved.csv", "data").size(), 2u * 15u);
}

}  // namespace
}  // namespace hnn::reliability
