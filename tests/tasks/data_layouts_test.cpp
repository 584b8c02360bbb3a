// Issue 28's data files: CSV separated by semicolons or tabs, the one-line messages of files
// that are not what their name says (binary, no header, another delimiter), derivative columns
// found by name (as `hnn simulate` writes them), and .npz archives of trajectories shaped
// (trajectories, times, components) (fixtures: tests/tasks/fixtures/make_numpy_fixtures.py).

#include <gtest/gtest.h>

#include "tasks/data/measured_dataset.h"
#include "tests/tasks/data_files_util.h"

namespace hnn::tasks {
namespace {

using testing::error_of;
using testing::fixture;
using Names = std::vector<std::string>;

class CsvLayouts : public testing::DataFilesTest {};
class DerivativeColumns : public testing::DataFilesTest {
 protected:
  // One trajectory of q = t^2, p = 3t (the differences are exact) with derivative columns
  // named `dq`, `dp` holding 100 + the truth, so that which source was used shows.
  std::string write_with(const std::string& dq, const std::string& dp) const {
    std::string text = fmt::format("t,q,p,{},{}\n", dq, dp);
    for (int i = 0; i < 5; ++i) {
      const double t = 0.5 * i;
      text += fmt::format("{},{},{},{},{}\n", t, t * t, 3 * t, 100 + 2 * t, 103.0);
    }
    return write("d.csv", text);
  }
};
class NpzTrajectories : public testing::DataFilesTest {};

TEST_F(CsvLayouts, SemicolonsAndTabsSeparateWhenTheHeaderUsesThem) {
  for (const std::string sep : {";", "\t"}) {
    const std::string text = "t" + sep + "q" + sep + "p\n0" + sep + "1.5" + sep + "2\n";
    const Table table = read_table(write("s.csv", text));
    EXPECT_EQ(table.names, (Names{"t", "q", "p"}));
    EXPECT_EQ(table.values.row(0), Eigen::RowVector3d(0, 1.5, 2));
  }
  EXPECT_EQ(read_table(write("c.csv", "\"a;b\",q\n1,2\n")).names, (Names{"a;b", "q"}));
}

TEST_F(CsvLayouts, FilesThatAreNotWhatTheyLookLikeGetOneLineSayingSo) {
  const struct Case {
    std::string name, bytes, message;
  } cases[] = {
      {"binary", std::string("t,q\n\0\x01\x02", 7), ": not a text CSV: it holds binary bytes"},
      {"npy", std::string("\x93NUMPY\x01\0", 8),
       ": not a text CSV: it holds binary bytes (it is a NumPy array: name it .npy)"},
      {"zip", std::string("PK\x03\x04\0\0", 6),
       ": not a text CSV: it holds binary bytes (it is a zip archive, e.g. .npz or .xlsx)"},
      {"headerless", "0,0,0\n1,2,3\n",
       ":1: the first row must name the columns (it holds numbers: 0,0,0); add a header row "
       "such as t,q,p"},
      {"semicolon_rows", "t,q,p\n0;0;0\n",
       ":2: 1 cells where the header names 3 columns (cells separated by ';'? then the header "
       "must be too)"},
      {"decimal_comma", "t;q\n0;1,5\n",
       ":2: column 'q': '1,5' is not a number (a decimal comma? write 0.5, not 0,5)"},
  };
  for (const Case& c : cases) {
    const std::string path = write(c.name + ".csv", c.bytes);
    EXPECT_EQ(error_of([&] { read_table(path); }), path + c.message) << c.name;
  }
}

TEST_F(DerivativeColumns, SimulatesNamesAndTheOthersAreFoundWhenEveryStateColumnHasOne) {
  for (const auto& [dq, dp] : {std::pair{"dq/dt", "dp/dt"}, std::pair{"dqdt", "dpdt"},
                               std::pair{"q_dot", "p_dot"}, std::pair{"dq_dt", "dp_dt"}}) {
    const MeasuredData d =
        load_measured_data(write_with(dq, dp), {.columns = {.coords = {"q"}, .momenta = {"p"}}});
    EXPECT_TRUE(d.derivatives_given && d.derivatives_by_name) << dq;
    EXPECT_EQ(d.derivative_names, (Names{dq, dp}));
    EXPECT_EQ(d.data.train_dxdt(0, 1), 103.0) << "the file's column, not differences";
    EXPECT_EQ(derivatives_source(d), d.source + ": dx/dt from the columns " + dq + ", " + dp +
                                         ", found by name (--derivatives names others; "
                                         "--derivatives none takes finite differences)");
  }
}

TEST_F(DerivativeColumns, PartlyFoundNoneOrOverriddenMeansWhatWasAsked) {
  const ColumnChoice state = {.coords = {"q"}, .momenta = {"p"}};
  const MeasuredData partial = load_measured_data(write_with("dq/dt", "other"), {.columns = state});
  EXPECT_FALSE(partial.derivatives_given);
  EXPECT_NEAR(partial.data.train_dxdt(0, 1), 3.0, 1e-12) << "differences";
  EXPECT_EQ(derivatives_source(partial),
            partial.source +
                ": dx/dt by finite differences within each trajectory (derivative columns dq/dt "
                "found, none for p: --derivatives names them all)");
  const std::string file = write_with("dq/dt", "dp/dt");
  ColumnChoice none = state;
  none.derivatives = {"none"};
  const MeasuredData differences = load_measured_data(file, {.columns = none});
  EXPECT_FALSE(differences.derivatives_given);
  EXPECT_EQ(derivatives_source(differences),
            file + ": dx/dt by finite differences within each trajectory (--derivatives none)");
  ColumnChoice named = state;
  named.derivatives = {"dp/dt", "dq/dt"};  // given: used as given, even swapped
  const MeasuredData given = load_measured_data(file, {.columns = named});
  EXPECT_FALSE(given.derivatives_by_name);
  EXPECT_EQ(given.data.train_dxdt(0, 0), 103.0);
  const MeasuredData plain =
      load_measured_data(write("plain.csv", "t,q,p\n0,0,0\n1,1,3\n2,4,6\n"), {.columns = state});
  EXPECT_EQ(derivatives_source(plain),
            plain.source +
                ": dx/dt by finite differences within each trajectory (no derivative columns "
                "such as dq/dt: --derivatives names them)");
}

TEST_F(NpzTrajectories, StatesOfTrajectoriesTimesAndComponentsWithTheirTimes) {
  const Table table = read_table(fixture("x_t_dx.npz"));
  EXPECT_EQ(table.names, (Names{"x[0]", "x[1]", "t", "dx[0]", "dx[1]", "trajectory"}));
  ASSERT_EQ(table.rows(), 18);         // 3 trajectories x 6 times
  EXPECT_EQ(table.values(7, 5), 1.0);  // row 7: trajectory 1, time 1
  EXPECT_DOUBLE_EQ(table.values(7, 2), 0.2);
  EXPECT_DOUBLE_EQ(table.values(7, 0), 2 * std::cos(0.2));
  // The state by its array's name, dx found by name as its derivatives, "t" as the time.
  const MeasuredData d = load_measured_data(fixture("x_t_dx.npz"),
                                            {.columns = {.coords = {"x[0]"}, .momenta = {"x[1]"}},
                                             .split = {.by = SplitBy::kTrajectories}});
  EXPECT_EQ(d.trajectories, 3);
  EXPECT_EQ(d.derivative_names, (Names{"dx[0]", "dx[1]"}));
  EXPECT_DOUBLE_EQ(d.data.train_dxdt(7, 1), -2 * std::cos(0.2));
}

TEST_F(NpzTrajectories, TimesPerTrajectoryAndOneDegreeOfFreedomArrays) {
  const Table times = read_table(fixture("states_times.npz"));
  EXPECT_EQ(times.names, (Names{"states[0]", "states[1]", "times", "trajectory"}));
  EXPECT_DOUBLE_EQ(times.values(6, 2), 10.0);  // trajectory 1 starts at t = 10
  const MeasuredData m =
      load_measured_data(fixture("states_times.npz"),
                         {.columns = {.coords = {"states[0]"}, .momenta = {"states[1]"}}});
  EXPECT_EQ(m.trajectories, 2);
  const Table qp = read_table(fixture("q_p_t.npz"));
  EXPECT_EQ(qp.names, (Names{"q", "p", "t", "trajectory"}));
  EXPECT_EQ(qp.rows(), 18);
  EXPECT_EQ(
      load_measured_data(fixture("q_p_t.npz"), {.columns = {.coords = {"q"}, .momenta = {"p"}}})
          .trajectories,
      3);
}

TEST_F(NpzTrajectories, AnArrayOfAnotherShapeIsNamed) {
  const std::string path = fixture("bad/trajectory_times.npz");
  EXPECT_EQ(error_of([&] { read_table(path); }),
            path +
                ": array 't': shape 4 does not fit 3 trajectories of 6 times (arrays of an "
                "archive of trajectories are 3x6xK states, 3x6 or 6 times, or 3 values per "
                "trajectory)");
}

}  // namespace
}  // namespace hnn::tasks
