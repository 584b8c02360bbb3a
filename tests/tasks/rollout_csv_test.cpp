// The one writer of the rollout CSV format (tasks/report/rollout_csv.h): header, digits, empty
// cells for what is missing, and rows left out of measured paths with gaps.

#include "tasks/report/rollout_csv.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hnn::tasks {
namespace {

TEST(RolloutCsv, PathsHaveOneRowPerTimeAndEmptyCellsForWhatIsMissing) {
  RolloutCsv csv({"q", "p"}, {.values = 4, .times = 3});
  Eigen::MatrixXd x(2, 2);
  x << 1.23456, NAN, 3, 4;
  csv.add("true", 0, std::vector<double>{0.0, 0.12345}, x, Eigen::Vector2d(0.5, 0.25));
  csv.add("hnn", 1, Eigen::VectorXd::Constant(1, 2.0), x.bottomRows(1), Eigen::VectorXd(),
          Eigen::VectorXd::Constant(1, INFINITY));
  EXPECT_EQ(csv.str(),
            "source,traj,t,q,p,energy,learned_h\n"
            "true,0,0,1.235,,0.5,\n"
            "true,0,0.123,3,4,0.25,\n"
            "hnn,1,2,3,4,,\n");
}

TEST(RolloutCsv, MeasuredPathsLeaveOutTheRowsOfMissingSamples) {
  RolloutCsv csv(numbered_columns("x", 2), {}, /*skip_incomplete=*/true);
  Eigen::MatrixXd x(3, 2);
  x << 1, 2, NAN, 3, 4, 5;
  csv.add("data", 0, std::vector<double>{0, 1, 2}, x);
  EXPECT_EQ(csv.str(),
            "source,traj,t,x_0,x_1,energy,learned_h\n"
            "data,0,0,1,2,,\n"
            "data,0,2,4,5,,\n");
}

}  // namespace
}  // namespace hnn::tasks
