// From a table to training data (tasks/data/measured_trajectories.h, measured_dataset.h): the
// column choices and their defaults, dx/dt exact on quadratics and never across a trajectory
// boundary or a gap, the splits, the held-out trajectories, and every bad choice or trajectory.

#include <gtest/gtest.h>

#include "tasks/data/measured_dataset.h"
#include "tests/tasks/data_files_util.h"

namespace hnn::tasks {
namespace {

using testing::error_of;
using testing::fixture;
using Names = std::vector<std::string>;

class MeasuredData_ : public testing::DataFilesTest {
 protected:
  // A CSV "time,id,q,p,dq,dp": per id k in `ids`, q = k + t + 3 t^2 and p = -k t^2 at `times`.
  std::string quadratic_csv(const std::vector<int>& ids, const std::vector<double>& times) {
    std::string text = "time,id,q,p,dq,dp\n";
    for (int k : ids) {
      for (double t : times) {
        text += fmt::format("{},{},{},{},{},{}\n", t, k, k + t + 3 * t * t, -k * t * t, 1 + 6 * t,
                            -2 * k * t);
      }
    }
    return write("quadratic.csv", text);
  }
  static ColumnChoice by_name() { return {.coords = {"q"}, .momenta = {"p"}, .trajectory = "id"}; }
};

std::string lipson(const std::string& file) {
  return std::string(HNN_SOURCE_DIR) + "/data/lipson/" + file;
}

// dq/dt = 1 + 6t, dp/dt = -2 k t for the rows of quadratic_csv.
void expect_exact_derivatives(const Segment& s) {
  for (Eigen::Index i = 0; i < s.t.size(); ++i) {
    const double t = s.t(i);
    EXPECT_NEAR(s.dxdt(i, 0), 1 + 6 * t, 1e-9) << "row " << i << " t " << t;
    EXPECT_NEAR(s.dxdt(i, 1), -2 * s.trajectory * t, 1e-9) << "row " << i << " t " << t;
  }
}

TEST(FiniteDifferences, ExactOnQuadraticsWithEvenAndUnevenStepsEndsIncluded) {
  for (const Eigen::VectorXd& t :
       {Eigen::VectorXd(Eigen::VectorXd::LinSpaced(7, 0, 1.2)),
        Eigen::VectorXd((Eigen::VectorXd(6) << 0, 0.1, 0.35, 0.4, 0.9, 1.0).finished())}) {
    Batch x(t.size(), 2);
    x.col(0) = (2 - 3 * t.array() + 5 * t.array().square()).matrix();
    x.col(1) = (t.array().square() / 4).matrix();
    const Batch dxdt = finite_differences(t, x);
    for (Eigen::Index i = 0; i < t.size(); ++i) {
      EXPECT_NEAR(dxdt(i, 0), -3 + 10 * t(i), 1e-12);
      EXPECT_NEAR(dxdt(i, 1), t(i) / 2, 1e-12);
    }
  }
}

TEST_F(MeasuredData_, ShippedLipsonFilesTakeTheirDefaults) {
  const MeasuredTrajectories real =
      select_trajectories(read_table(lipson("real_pend_h_1.txt")), {});
  EXPECT_EQ(real.state_names, (Names{"o", "v"}));
  EXPECT_TRUE(real.velocities);
  EXPECT_FALSE(real.derivatives_given);
  EXPECT_EQ(real.time_name, "t");
  EXPECT_EQ(real.trajectory_name, "trial");
  EXPECT_EQ(real.gaps, 10);  // dropped frames: steps of 1/3 s and 1/2 s where 1/6 s is usual
  EXPECT_EQ(real.dropped_rows, 0);
  const MeasuredData split = split_trajectories(real, {});
  EXPECT_EQ(split.split, SplitBy::kTime);
  EXPECT_EQ(split.data.test_x.rows(), 111);  // round(0.2 * 556)
  EXPECT_EQ(split.data.train_x.rows(), 445);
  EXPECT_NE(describe(split).find("velocities taken as momenta: unit masses assumed"),
            std::string::npos)
      << describe(split);

  const MeasuredData two = load_measured_data(lipson("real_double_pend_h_1.txt"));
  EXPECT_EQ(two.state_names, (Names{"o1", "o2", "w1", "w2"}));
  EXPECT_EQ(two.split, SplitBy::kTrajectories);
  EXPECT_EQ(two.trajectories, 2);
  EXPECT_EQ(two.test_trajectories, 1);
  EXPECT_EQ(two.data.train_x.rows() + two.data.test_x.rows() + two.dropped_rows, 1520);
  for (const HeldOut& h : two.held_out) EXPECT_EQ(h.trajectory, 1.0);
}

TEST_F(MeasuredData_, LipsonDerivativeColumnsCanBeChosen) {
  MeasuredDataOptions options;
  options.columns = {.coords = {"o"}, .velocities = {"v"}, .derivatives = {"do", "dv"}};
  const MeasuredData d = load_measured_data(lipson("pendulum_h_1.txt"), options);
  EXPECT_TRUE(d.derivatives_given);
  EXPECT_EQ(d.data.train_dxdt(0, 0), 0.01);  // the file's first row: do = 1e-2, dv = -9.8
  EXPECT_EQ(d.data.train_dxdt(0, 1), -9.8000000000000007);
}

TEST_F(MeasuredData_, CsvColumnsByNameOrIndexGiveTheSameData) {
  const std::string path = quadratic_csv({1, 2}, {0, 0.1, 0.2, 0.3, 0.4});
  const MeasuredTrajectories named = select_trajectories(read_table(path), by_name());
  const MeasuredTrajectories indexed = select_trajectories(
      read_table(path), {.coords = {"2"}, .momenta = {"3"}, .time = "0", .trajectory = "1"});
  EXPECT_EQ(named.time_name, "time");  // found by its name
  ASSERT_EQ(named.segments.size(), 2u);
  for (const MeasuredTrajectories* m : {&named, &indexed}) {
    EXPECT_EQ(m->state_names, (Names{"q", "p"}));
    EXPECT_FALSE(m->velocities);
    EXPECT_EQ(m->trajectory_ids, (std::vector<double>{1, 2}));
    for (const Segment& s : m->segments) expect_exact_derivatives(s);
  }
  ColumnChoice given = by_name();
  given.derivatives = {"dq", "dp"};
  const MeasuredTrajectories with = select_trajectories(read_table(path), given);
  EXPECT_TRUE(with.derivatives_given);
  EXPECT_TRUE(with.segments[1].dxdt.isApprox(named.segments[1].dxdt, 1e-12))
      << "the file's exact derivatives equal the (exact) differences";
}

TEST_F(MeasuredData_, NumpyFilesByIndexAndByArrayName) {
  const MeasuredTrajectories npy = select_trajectories(
      read_table(fixture("quadratic.npy")), {.coords = {"1"}, .momenta = {"2"}, .time = "0"});
  const MeasuredTrajectories npz =
      select_trajectories(read_table(fixture("two_dof.npz")), {.coords = {"q"}, .momenta = {"p"}});
  EXPECT_EQ(npz.state_names, (Names{"q[0]", "q[1]", "p[0]", "p[1]"}));
  EXPECT_EQ(npz.coordinates, 2);
  for (Eigen::Index i = 0; i < 6; ++i) {
    const double t = 0.2 * double(i);  // q = 1 + 2t + 3t^2, p = -t^2 (make_numpy_fixtures.py)
    EXPECT_NEAR(npy.segments[0].dxdt(i, 0), 2 + 6 * t, 1e-12);
    EXPECT_NEAR(npy.segments[0].dxdt(i, 1), -2 * t, 1e-12);
    EXPECT_NEAR(npz.segments[0].dxdt(i, 1), -(2 + 6 * t), 1e-12);
    EXPECT_NEAR(npz.segments[0].dxdt(i, 3), -6 * t, 1e-12);
  }
  const MeasuredTrajectories two = select_trajectories(read_table(fixture("two_trajectories.npz")),
                                                       {.coords = {"q"}, .momenta = {"p"}});
  EXPECT_EQ(two.trajectory_name, "trajectory");
  EXPECT_EQ(two.trajectory_ids.size(), 2u);
}

TEST_F(MeasuredData_, NoDifferenceReachesAcrossATrajectoryBoundaryOrAGap) {
  // Ids 1 and 2 interleave in the file: each is still its own trajectory, in file order.
  const std::string interleaved =
      write("mixed.csv",
            "time,id,q,p\n0,1,1,0\n0,2,2,0\n0.1,1,1.13,-0.01\n0.1,2,2.13,-0.02\n"
            "0.2,1,1.32,-0.04\n0.2,2,2.32,-0.08\n");
  const MeasuredTrajectories m = select_trajectories(read_table(interleaved), by_name());
  ASSERT_EQ(m.segments.size(), 2u);
  for (const Segment& s : m.segments) expect_exact_derivatives(s);
  EXPECT_EQ(m.segments[1].rows, (std::vector<Eigen::Index>{1, 3, 5}));

  // One trajectory with a gap at 0.3 -> 1.0 and a jump across it that a difference would see.
  std::string text = "time,id,q,p\n";
  for (double t : {0.0, 0.1, 0.2, 0.3})
    text += fmt::format("{},1,{},{}\n", t, 1 + t + 3 * t * t, -t * t);
  for (double t : {1.0, 1.1, 1.2})
    text += fmt::format("{},1,{},{}\n", t, 50 + t + 3 * t * t, -t * t);
  const MeasuredTrajectories gap =
      select_trajectories(read_table(write("gap.csv", text)), by_name());
  EXPECT_EQ(gap.gaps, 1);
  ASSERT_EQ(gap.segments.size(), 2u);
  for (const Segment& s : gap.segments) expect_exact_derivatives(s);

  ColumnChoice never = by_name();
  never.gap_factor = 0;
  EXPECT_EQ(select_trajectories(read_table(write("gap.csv", text)), never).segments.size(), 1u);
}

TEST_F(MeasuredData_, StretchesTooShortBetweenGapsAreLeftOutAndCounted) {
  const std::string path = write(
      "short.csv", "t,q,p\n0,0,0\n1,1,1\n2,4,4\n3,9,9\n10,1,1\n11,2,2\n20,0,0\n21,1,1\n22,2,2\n");
  const MeasuredTrajectories m =
      select_trajectories(read_table(path), {.coords = {"q"}, .momenta = {"p"}});
  EXPECT_EQ(m.gaps, 2);
  EXPECT_EQ(m.dropped_rows, 2);  // t = 10, 11
  ASSERT_EQ(m.segments.size(), 2u);
  EXPECT_EQ(m.segments[1].t(0), 20.0);
}

TEST_F(MeasuredData_, SplitsByWholeTrajectoriesOrByTime) {
  const std::string path = quadratic_csv({1, 2, 3, 4, 5}, {0, 0.1, 0.2, 0.3, 0.4});
  const MeasuredTrajectories m = select_trajectories(read_table(path), by_name());
  const MeasuredData last = split_trajectories(m, {});
  EXPECT_EQ(last.split, SplitBy::kTrajectories);
  EXPECT_EQ(last.data.train_x.rows(), 20);
  ASSERT_EQ(last.held_out.size(), 1u);
  EXPECT_EQ(last.held_out[0].trajectory, 5);
  EXPECT_EQ(last.held_out[0].where, path + ":22");
  EXPECT_EQ(last.held_out[0].t, m.segments[4].t);
  EXPECT_EQ(last.held_out[0].x, m.segments[4].x);
  EXPECT_EQ(last.data.test_dxdt, m.segments[4].dxdt);

  const MeasuredData two =
      split_trajectories(m, {.by = SplitBy::kTrajectories, .test_fraction = 0.4});
  EXPECT_EQ(two.test_trajectories, 2);
  EXPECT_EQ(two.held_out[0].trajectory, 4);

  const MeasuredData time = split_trajectories(m, {.by = SplitBy::kTime, .test_fraction = 0.4});
  EXPECT_EQ(time.data.train_x.rows(), 15);  // 3 of each trajectory's 5 rows
  ASSERT_EQ(time.held_out.size(), 5u);
  for (const HeldOut& h : time.held_out) EXPECT_EQ(h.t, Eigen::Vector2d(0.3, 0.4));
  EXPECT_EQ(time.data.test_x.row(0), m.segments[0].x.row(3));

  const MeasuredData again = split_trajectories(m, {});
  EXPECT_EQ(again.data.test_x, last.data.test_x);  // deterministic
}

TEST_F(MeasuredData_, BadSplitChoicesAreRefused) {
  const MeasuredTrajectories one =
      select_trajectories(read_table(quadratic_csv({1}, {0, 0.1, 0.2, 0.3})), by_name());
  EXPECT_EQ(error_of([&] { split_trajectories(one, {.by = SplitBy::kTrajectories}); }),
            one.table.source +
                ": a split by trajectories needs at least 2, and the file has 1 "
                "(split by time instead)");
  for (double f : {0.0, 1.0, -0.5, std::nan("")}) {
    EXPECT_EQ(error_of([&] { split_trajectories(one, {.test_fraction = f}); }),
              fmt::format("test fraction {} is not between 0 and 1", f));
  }
}

}  // namespace
}  // namespace hnn::tasks
