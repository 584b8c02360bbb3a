// Every bad column choice and every bad trajectory of tasks/data/measured_trajectories.h, each
// with its whole one-line message (docs/inputs.md lists them).

#include <gtest/gtest.h>

#include <cmath>

#include "tasks/data/measured_dataset.h"
#include "tests/tasks/data_files_util.h"

namespace hnn::tasks {
namespace {

using testing::error_of;
using testing::fixture;

class MeasuredDataErrors : public testing::DataFilesTest {
 protected:
  // The message of selecting `choice` from a file of `text`, with the file's path cut off.
  std::string message(const std::string& text, const ColumnChoice& choice,
                      const std::string& name = "d.csv") {
    const std::string path = write(name, text);
    std::string m = error_of([&] { select_trajectories(read_table(path), choice); });
    return m.rfind(path, 0) == 0 ? "FILE" + m.substr(path.size()) : m;
  }
  static constexpr const char* kFile = "time,id,q,p,dq\n0,1,0,0,0\n0.1,1,1,1,1\n0.2,1,2,2,2\n";
};

ColumnChoice qp() { return {.coords = {"q"}, .momenta = {"p"}}; }

TEST_F(MeasuredDataErrors, BadColumnChoices) {
  EXPECT_EQ(message(kFile, {.coords = {"x"}, .momenta = {"p"}}),
            "FILE: no column 'x' (columns: time, id, q, p, dq)");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .momenta = {"7"}}),
            "FILE: no column 7 (the file has 5 columns, numbered from 0: time, id, q, p, dq)");
  EXPECT_EQ(message(kFile, {}),
            "FILE: which columns are the coordinates? give coords, and momenta or velocities "
            "(columns: time, id, q, p, dq)");
  EXPECT_EQ(message(kFile, {.coords = {"q"}}),
            "FILE: give either momenta or velocities for the coordinates (neither was given)");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .momenta = {"p"}, .velocities = {"dq"}}),
            "FILE: give either momenta or velocities for the coordinates (not both)");
  EXPECT_EQ(message(kFile, {.coords = {"q", "dq"}, .momenta = {"p"}}),
            "FILE: 2 coordinates (q, dq) but 1 momenta (p): each coordinate needs one");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .velocities = {"p", "dq"}}),
            "FILE: 1 coordinates (q) but 2 velocities (p, dq): each coordinate needs one");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .momenta = {"p"}, .derivatives = {"dq"}}),
            "FILE: 1 derivative columns (dq) for a state of 2: give dx/dt of every coordinate, "
            "then of every momentum");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .momenta = {"q"}}),
            "FILE: column 'q' is chosen twice (as a coordinate and as a momentum)");
  EXPECT_EQ(message(kFile, {.coords = {"time"}, .momenta = {"p"}}),
            "FILE: column 'time' is chosen twice (as the time and as a coordinate)");
  EXPECT_EQ(message(kFile, {.coords = {"q"}, .momenta = {"p"}, .trajectory = "q"}),
            "FILE: column 'q' is chosen twice (as the trajectory id and as a coordinate)");
  EXPECT_EQ(message("a,q,p\n0,0,0\n", qp()),
            "FILE: no time column (none is named t, time or times) and no derivative columns: "
            "give the time column by name or index, or for scattered states dx/dt of every state "
            "column (named d<x>/dt, or chosen with --derivatives) (columns: a, q, p)");
  // Some derivative columns found, not all: the note says which.
  EXPECT_EQ(message("q,p,dq/dt\n0,0,0\n", qp()),
            "FILE: no time column (none is named t, time or times) and no derivative columns "
            "(derivative columns dq/dt found, none for p: --derivatives names them all): give the "
            "time column by name or index, or for scattered states dx/dt of every state column "
            "(named d<x>/dt, or chosen with --derivatives) (columns: q, p, dq/dt)");
}

// A file without a time column but with every derivative column: scattered states, split by
// rows (the last are the test set), with no trajectories or stretches.
TEST_F(MeasuredDataErrors, ScatteredStatesAreReadWithoutTime) {
  const std::string csv = "q,p,dq/dt,dp/dt\n1,2,3,4\n5,6,7,8\n9,10,11,12\n13,14,15,16\n";
  const std::string path = write("s.csv", csv);
  const MeasuredTrajectories m = select_trajectories(read_table(path), qp());
  EXPECT_TRUE(m.scattered);
  ASSERT_EQ(m.segments.size(), 1u);
  EXPECT_EQ(m.segments[0].t.size(), 0);
  const MeasuredData d = split_trajectories(m, {.test_fraction = 0.25});
  EXPECT_TRUE(d.scattered);
  ASSERT_EQ(d.data.train_x.rows(), 3);
  ASSERT_EQ(d.data.test_x.rows(), 1);
  EXPECT_EQ(d.data.test_x(0, 1), 14);
  EXPECT_EQ(d.data.test_dxdt(0, 0), 15);
  EXPECT_EQ(d.data.train_dxdt(2, 1), 12);
  EXPECT_TRUE(d.held_out.empty());
  EXPECT_TRUE(d.train_stretches.empty());
  EXPECT_NE(describe(d).find("split by rows: 3 training rows, 1 test rows"), std::string::npos)
      << describe(d);
  EXPECT_EQ(error_of([&] { split_trajectories(m, {.by = SplitBy::kTrajectories}); }),
            path +
                ": split by trajectories needs trajectories, and the file holds scattered states "
                "(no time column): leave the split at auto (the last rows are the test set)");
}

TEST_F(MeasuredDataErrors, NpzCoordinatesAndMomentaOfDifferentCounts) {
  const std::string path = fixture("two_dof.npz");
  EXPECT_EQ(error_of([&] {
              select_trajectories(read_table(path), {.coords = {"q"}, .momenta = {"p[0]"}});
            }),
            path + ": 2 coordinates (q[0], q[1]) but 1 momenta (p[0]): each coordinate needs one");
}

TEST_F(MeasuredDataErrors, BadTrajectories) {
  EXPECT_EQ(message("t,id,q,p\n0,1,0,0\n1,1,1,1\n2,1,4,4\n0,2,0,0\n1,2,1,1\n",
                    {.coords = {"q"}, .momenta = {"p"}, .trajectory = "id"}),
            "FILE:5: trajectory 2 has 2 points; at least 3 are needed");
  EXPECT_EQ(message("t,q,p\n\n0,0,0\n", qp()),
            "FILE:3: the file's one trajectory has 1 point; at least 3 are needed");
  EXPECT_EQ(message("t,trial,q,p\n0,1,0,0\n0.2,1,1,1\n0.1,1,4,4\n", qp()),
            "FILE:4: time does not increase within trajectory 1 (t = 0.2 then 0.1)");
  EXPECT_EQ(message("t,q,p\n0,0,0\n0.1,1,1\n0.1,4,4\n", qp()),
            "FILE:4: time does not increase within the file's one trajectory (t = 0.1 then 0.1)");
  // Trajectories one after another with no id column: time starts again.
  EXPECT_EQ(message("t,q,p\n0,0,0\n1,1,1\n2,4,4\n0,0,0\n1,1,1\n2,4,4\n", qp()),
            "FILE:5: time does not increase within the file's one trajectory (t = 2 then 0)");
  EXPECT_EQ(message("t,q,p\n0,0,0\n1,1,1\n10,4,4\n11,0,0\n20,1,1\n21,4,4\n", qp()),
            "FILE: every stretch between gaps in time has fewer than 3 points, too few to "
            "difference (raise the gap factor, or give derivative columns)");
}

TEST_F(MeasuredDataErrors, LipsonHeaderThatDoesNotHalve) {
  EXPECT_EQ(message("% x y z\n0 0 1 2 3\n0 1 1 2 3\n0 2 1 2 3\n", {}, "odd.txt"),
            "FILE: the '%' header names 3 state columns (x y z), which do not halve into "
            "coordinates and velocities: give coords and velocities");
}

TEST_F(MeasuredDataErrors, BadGapFactors) {
  for (double factor : {1.0, 0.5, -1.0, double(INFINITY), std::nan("")}) {
    ColumnChoice choice = qp();
    choice.gap_factor = factor;
    EXPECT_EQ(
        message(kFile, choice),
        fmt::format("gap factor {} is neither 0 (never cut) nor a finite number > 1", factor));
  }
}

}  // namespace
}  // namespace hnn::tasks
