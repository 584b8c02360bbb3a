// The one writer of each rollout CSV format (tasks/report/rollout_csv.h): headers, digits, empty
// cells for what is missing, and rows left out of measured paths with gaps.

#include "tasks/report/rollout_csv.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hnn::tasks {
namespace {

TEST(RolloutCsv, PathsHaveOneRowPerTimeAndEmptyCellsForWhatIsMissing) {
  PathsCsv csv({"q", "p"}, {.values = 4, .times = 3});
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
  PathsCsv csv(numbered_columns("x", 2), {}, /*skip_incomplete=*/true);
  Eigen::MatrixXd x(3, 2);
  x << 1, 2, NAN, 3, 4, 5;
  csv.add("measured", 0, std::vector<double>{0, 1, 2}, x);
  EXPECT_EQ(csv.str(),
            "source,traj,t,x_0,x_1,energy,learned_h\n"
            "measured,0,0,1,2,,\n"
            "measured,0,2,4,5,,\n");
}

TEST(RolloutCsv, ComparisonsPutTheTruthBesideThePrediction) {
  ComparisonCsv csv(1, {.times = 12});
  csv.add(0, Eigen::Vector2d(0, 1.0 / 3), Eigen::Vector2d(1, 2), Eigen::Vector2d(1.5, NAN),
          Eigen::Vector2d(7, 8), Eigen::VectorXd(), Eigen::Vector2d(9, 10));
  EXPECT_EQ(csv.str(),
            "traj,t,true_0,pred_0,true_energy,pred_energy,learned_h\n"
            "0,0,1,1.5,7,,9\n"
            "0,0.333333333333,2,,8,,10\n");
}

}  // namespace
}  // namespace hnn::tasks
