// `hnn hamiltonian`: a run's learned H and the true energy on a 2-D slice of its state space, as
// CSV (apps/hnn/commands/hamiltonian.cpp). Its values are those `hnn rollout` reports at the same
// states (the learned H of the model's path at t = 0, the true energy of the truth's), in the data
// file's units for a data run; a baseline and bad slices are refused in one line, with no file
// (docs/inputs.md).

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "reliability_util.h"

namespace hnn::reliability {
namespace {

const char* const kQuartic = "(px^2+py^2)/2 + (x^2+y^2)/2 + 0.5*x^2*y^2";

std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char c : line) {
    if (c == ',') {
      cells.emplace_back();
    } else {
      cells.back().push_back(c);
    }
  }
  return cells;
}

// The first row of `source` in a rollout CSV (source,traj,t,<state>,energy,learned_h).
std::vector<std::string> first_row_of(const fs::path& csv, const std::string& source) {
  for (const std::string& line : lines(read_text(csv)))
    if (line.starts_with(source + ",")) return cells_of(line);
  return {};
}

// A 2-degree-of-freedom data run trained with its H, and a baseline of the same file.
class HamiltonianGrid : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("HamiltonianGrid");
    ASSERT_EQ(run_hnn({"simulate", "--hamiltonian", kQuartic, "--coords", "x,y", "--momenta",
                       "px,py", "--trajectories", "6", "--t-end", "2", "--points", "12", "--out",
                       (*dir_ / "quartic.csv").string()},
                      dir_->path())
                  .code,
              0);
    for (const char* model : {"hnn", "baseline"}) {
      ASSERT_EQ(
          run_hnn({"train", "data", "--data", (*dir_ / "quartic.csv").string(), "--coords", "x,y",
                   "--momenta", "px,py", "--hamiltonian", kQuartic, "--model", model, "--steps",
                   "10", "--hidden", "8", "--quiet", "--out", (*dir_ / model).string()},
                  dir_->path())
              .code,
          0);
    }
  }
  static void TearDownTestSuite() { delete dir_; }

  static Result grid(const std::string& model, std::vector<std::string> extra) {
    std::vector<std::string> args = {"hamiltonian", (*dir_ / model).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_hnn(args, dir_->path());
  }

  static TempDir* dir_;
};
TempDir* HamiltonianGrid::dir_ = nullptr;

TEST_F(HamiltonianGrid, WritesTheSliceWithTheValuesRolloutReports) {
  const Result r =
      grid("hnn", {"--grid", "x=-1:1,px=-1:1", "--at", "py=0, y=0.5", "--points", "3"});
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path csv = *dir_ / "hnn" / "h_grid_x_px.csv";  // the default
  EXPECT_NE(r.out.find("hnn hamiltonian: 9 points of the learned H and the true energy -> " +
                       csv.string()),
            std::string::npos)
      << r.out;
  const std::vector<std::string> rows = lines(read_text(csv));
  ASSERT_EQ(rows.size(), 10u);
  EXPECT_EQ(rows[0], "x,px,y,py,learned_h,energy");
  const std::vector<std::string> first = cells_of(rows[1]), second = cells_of(rows[2]);
  EXPECT_EQ(std::vector<std::string>(first.begin(), first.begin() + 4),
            std::vector<std::string>({"-1", "-1", "0.5", "0"}));
  EXPECT_EQ(std::vector<std::string>(second.begin(), second.begin() + 4),
            std::vector<std::string>({"0", "-1", "0.5", "0"}));  // x varies fastest
  EXPECT_EQ(first[5], "1.25");  // (1 + 0)/2 + (1 + 0.25)/2 + 0.5 * 1 * 0.25

  // The same state through `hnn rollout`: the same learned H (file units) and true energy.
  const fs::path rollout = *dir_ / "rollout.csv";
  ASSERT_EQ(run_hnn({"rollout", "hnn", "--state", "-1,0.5,-1,0", "--points", "2", "--out",
                     rollout.string()},
                    dir_->path(), dir_->path())
                .code,
            0);
  EXPECT_EQ(first_row_of(rollout, "hnn").at(8), first[4]);
  EXPECT_EQ(first_row_of(rollout, "true").at(7), first[5]);
}

TEST_F(HamiltonianGrid, RefusesABaselineAndBadSlicesInOneLine) {
  const fs::path out = *dir_ / "bad.csv";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--grid", "x=-1:1,px=-1:1", "--at", "y=0,py=0"}, "a baseline model learns no scalar H"},
      {{"--grid", "x=-1:1"}, "--grid 'x=-1:1': expected two state columns NAME=LO:HI"},
      {{"--grid", "x=1:-1,px=-1:1", "--at", "y=0,py=0"}, "--grid 'x=1:-1': LO must be below HI"},
      {{"--grid", "x=-1:1,z=0:1", "--at", "y=0,py=0"}, "--grid: 'z' is not a state column"},
      {{"--grid", "x=-1,px=0:1", "--at", "y=0,py=0"}, "--grid 'x=-1': the range is not LO:HI"},
      {{"--grid", "x=-1:a,px=0:1", "--at", "y=0,py=0"}, "--grid 'x=-1:a': HI: 'a' is not a"},
      {{"--grid", "x=-1:1,px=-1:1", "--at", "y=0"}, "--at: no value for py:"},
      {{"--grid", "x=-1:1,px=-1:1", "--at", "y=0,py=0,x=1"}, "--at: state column 'x' is named"},
      {{"--grid", "x=-1:1,px=-1:1", "--at", "y=0,py=0", "--points", "1"}, "--points: expected"},
  };
  for (const auto& [extra, message] : cases) {
    std::vector<std::string> args = extra;
    args.insert(args.end(), {"--out", out.string()});
    const bool baseline = message.starts_with("a baseline");
    const Result r = grid(baseline ? "baseline" : "hnn", args);
    const std::string what = fmt::format("{}", fmt::join(extra, " "));
    expect_one_line_error_starting(r, message, what);
    EXPECT_FALSE(fs::exists(out)) << what;
  }
}

TEST(HamiltonianGridOfATask, ATaskSystemGivesTheTrueEnergyUnderNumberedColumns) {
  const TempDir dir;
  ASSERT_EQ(run_hnn({"train", "spring", "--steps", "5", "--hidden", "8", "--quiet", "--out",
                     (dir / "run").string()},
                    dir.path())
                .code,
            0);
  const Result r = run_hnn({"hamiltonian", (dir / "run").string(), "--grid", "x_1=0:2,x_0=-1:1",
                            "--points", "2", "--out", (dir / "g.csv").string()},
                           dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> rows = lines(read_text(dir / "g.csv"));
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[0], "x_1,x_0,learned_h,energy");
  const fs::path rollout = dir / "rollout.csv";
  ASSERT_EQ(run_hnn({"rollout", (dir / "run").string(), "--state", "1,2", "--points", "2", "--out",
                     rollout.string()},
                    dir.path())
                .code,
            0);
  const std::vector<std::string> last = cells_of(rows[4]);  // x_1 = 2, x_0 = 1
  ASSERT_EQ(std::vector<std::string>(last.begin(), last.begin() + 2),
            std::vector<std::string>({"2", "1"}));
  EXPECT_EQ(first_row_of(rollout, "true").at(5), last[3]);
  EXPECT_EQ(first_row_of(rollout, "hnn").at(6), last[2]);
}

// A CHNN learns V with the known masses: its energy 1/2 v^T M v + V is what its motion conserves.
// `hnn rollout` writes it in the learned_h column, constant along the learned path, and `hnn
// hamiltonian` draws it on a slice.
TEST(HamiltonianGridOfATask, AChnnRunGivesItsLearnedEnergyConservedAlongItsRollouts) {
  const TempDir dir;
  ASSERT_EQ(run_hnn({"train", "chain-pendulum-2", "--model", "chnn", "--steps", "2", "--batch", "4",
                     "--hidden", "8", "--settings",
                     R"({"trajectories": 6, "validation": 2, "rollouts": 2})", "--quiet", "--out",
                     (dir / "run").string()},
                    dir.path())
                .code,
            0);
  const fs::path rollout = dir / "rollout.csv";
  ASSERT_EQ(run_hnn({"rollout", (dir / "run").string(), "--trajectories", "2", "--points", "30",
                     "--out", rollout.string()},
                    dir.path())
                .code,
            0);
  std::map<std::string, std::pair<double, double>> range;  // per trajectory: min, max
  for (const std::string& line : lines(read_text(rollout))) {
    if (!line.starts_with("chnn,")) continue;
    const std::vector<std::string> cells = cells_of(line);
    ASSERT_EQ(cells.size(), 13u) << line;  // source, traj, t, 8 state columns, energy, learned_h
    ASSERT_FALSE(cells[12].empty()) << line;
    const double h = std::stod(cells[12]);
    auto [it, fresh] = range.try_emplace(cells[1], h, h);
    it->second = {std::min(it->second.first, h), std::max(it->second.second, h)};
  }
  ASSERT_EQ(range.size(), 2u);
  for (const auto& [traj, r] : range) {
    EXPECT_LT(r.second - r.first, 1e-6 * std::max(1.0, std::abs(r.first))) << "trajectory " << traj;
  }
  const Result grid = run_hnn(
      {"hamiltonian", (dir / "run").string(), "--grid", "x_0=-1:1,x_1=-2:0", "--at",
       "x_2=0,x_3=-2,x_4=0,x_5=0,x_6=0,x_7=0", "--points", "2", "--out", (dir / "g.csv").string()},
      dir.path());
  ASSERT_EQ(grid.code, 0) << grid.err;
  EXPECT_EQ(lines(read_text(dir / "g.csv")).size(), 5u);
}

}  // namespace
}  // namespace hnn::reliability
