// The peer's relative-error metric and floor for constrained systems
// (physics/constrained/metric.h), on hand-made inputs and on the two-link chain.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>

#include "physics/constrained/metric.h"
#include "physics/constrained/systems.h"

namespace hnn::physics::constrained {
namespace {

TEST(ConstrainedMetric, RelativeErrorsOnHandMadeRows) {
  Batch predicted(3, 2), truth(3, 2);
  predicted << 3.0, 4.0, 1.0, 2.0, 1.0, 0.0;
  truth << 0.0, 0.0, 1.0, 2.0, 0.0, 1.0;
  const Eigen::VectorXd e = relative_errors(predicted, truth);
  EXPECT_DOUBLE_EQ(e[0], 1.0);  // |z^ - 0| / (|z^| + 0)
  EXPECT_DOUBLE_EQ(e[1], 0.0);
  EXPECT_NEAR(e[2], std::sqrt(2.0) / 2.0, 1e-15);
  EXPECT_THROW(relative_errors(predicted, truth.leftCols(1)), std::invalid_argument);
}

TEST(ConstrainedMetric, GeometricMeansOverTimeAndTrajectories) {
  // Trapezoid of log(e + 1e-8) times dt over the horizon (the peer's notebook).
  const Eigen::Vector3d errors(1e-2, 1e-4, 1e-2);
  const double expected = std::exp(
      0.5 * (0.5 * std::log(1e-2 + 1e-8) + std::log(1e-4 + 1e-8) + 0.5 * std::log(1e-2 + 1e-8)) /
      1.0);
  EXPECT_NEAR(trajectory_geometric_mean(errors, 0.5, 1.0), expected, 1e-15);
  EXPECT_NEAR(trajectory_geometric_mean(Eigen::Vector2d(0.0, 0.0), 1.0, 1.0), 1e-8, 1e-20);
  EXPECT_NEAR(pooled_geometric_mean(Eigen::Vector2d(1e-2, 1e-4)), 1e-3, 1e-17);
  EXPECT_THROW(trajectory_geometric_mean(Eigen::VectorXd::Ones(1), 1.0, 1.0),
               std::invalid_argument);
}

TEST(ConstrainedMetric, FailedRolloutsAreCountedNotPooled) {
  std::vector<Batch> truth(3, Batch::Ones(2, 2)), predicted = truth;
  for (Batch& b : predicted) b(0, 0) = 3.0;  // row 0: error 2 / (sqrt(10) + sqrt(2)) each time
  predicted[2](1, 1) = std::nan("");         // row 1 fails at the last time
  const RolloutScore score = score_rollouts(predicted, truth, 1.0, 2.0);
  EXPECT_EQ(score.failed, 1);
  EXPECT_TRUE(std::isnan(score.per_trajectory[1]));
  const double e = 2.0 / (std::sqrt(10.0) + std::sqrt(2.0)) + 1e-8;
  EXPECT_NEAR(score.per_trajectory[0], e, 1e-15);
  EXPECT_NEAR(score.geometric_mean, e, 1e-15);
}

TEST(ConstrainedMetric, FloorOfTheTwoLinkChainStartsOnTheManifoldNearTheTruth) {
  const ConstrainedSystem system = chain_pendulum(2);
  std::mt19937_64 rng(2);
  const Batch z0 = system.sample_initial_states(4, rng);
  const std::vector<Batch> truth = simulate_constrained(system, z0, system.output_times()).states;
  const FloorResult floor = floor_score(system, z0, truth, rng);
  const Batch& start = floor.perturbed.front();
  EXPECT_LT(system.constraint_values(start).cwiseAbs().maxCoeff(), 1e-11);
  EXPECT_LT(system.constraint_velocities(start).cwiseAbs().maxCoeff(), 1e-10);
  const double moved = (start - z0).cwiseAbs().maxCoeff();
  EXPECT_GT(moved, 1e-6);
  EXPECT_LT(moved, 1e-3);
  std::printf("two-link chain floor over 4 starts: %.2e (the peer's: 5.9e-5 over 100)\n",
              floor.score.geometric_mean);
  EXPECT_EQ(floor.score.failed, 0);
  EXPECT_GT(floor.score.geometric_mean, 1e-6);
  EXPECT_LT(floor.score.geometric_mean, 1e-3);
  EXPECT_THROW(floor_score(system, z0, {truth.front()}, rng), std::invalid_argument);
}

TEST(ConstrainedData, ChunksAreConsecutiveTruthFromRandomStarts) {
  const ConstrainedSystem system = magnet_pendulum();
  std::mt19937_64 rng(1);
  const ChunkSample sample = sample_chunks(system, 6, 5, rng);
  ASSERT_EQ(sample.states.size(), 5u);
  std::set<int> starts(sample.first_output.begin(), sample.first_output.end());
  EXPECT_GT(starts.size(), 1u);  // random chunks, not all the first
  for (int start : starts) EXPECT_TRUE(start % 5 == 0 && start >= 0 && start < 100);
  // Each chunk is the truth from its first state, dt apart.
  const Trajectory again = simulate_constrained(system, sample.states.front(),
                                                {0.0, system.spec().dt, 2 * system.spec().dt});
  EXPECT_LT((again.states[2] - sample.states[2]).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_THROW(sample_chunks(system, 2, 3, rng), std::invalid_argument);  // 100 % 3 != 0
}

}  // namespace
}  // namespace hnn::physics::constrained
