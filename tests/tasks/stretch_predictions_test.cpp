// Held-out stretches predicted from their first states (tasks/evaluate/stretch_predictions.h):
// one batch, or one stretch at a time with each failure kept at its place.

#include "tasks/evaluate/stretch_predictions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "autodiff/parallel.h"

namespace hnn::tasks {
namespace {

// dq/dt = q^2, dp/dt = 0: q(t) = q0 / (1 - q0 t), which blows up at t = 1 / q0 for q0 > 0.
const physics::VectorField kExplosive = [](double, const Batch& x, Batch& dxdt) {
  dxdt = Batch::Zero(x.rows(), 2);
  dxdt.col(0) = x.col(0).array().square();
};

std::vector<Stretch> stretches_from(const std::vector<double>& q0s) {
  std::vector<Stretch> out;
  for (double q0 : q0s) {
    Batch x = Batch::Zero(11, 2);
    x(0, 0) = q0;
    out.push_back({Eigen::VectorXd::LinSpaced(11, 0.0, 1.0), x});
  }
  return out;
}

// One at a time (adaptive steps, as the data task asks): each stretch gets its own path, the
// same at any thread count, and a stretch that blows up fails alone, at its place.
TEST(PredictPaths, OneAtATimeGivesEachStretchItsOwnPathAndFailure) {
  const std::vector<Stretch> stretches = stretches_from({-1.0, 2.0, -0.5, 0.25, -2.0});
  const Predictor predict = dopri5_predictor(kExplosive);
  const int previous = ad::num_threads();
  std::vector<PredictedPaths> by_threads;
  for (int threads : {1, 2}) {
    ad::set_num_threads(threads);
    by_threads.push_back(predict_paths(stretches, predict, /*batch=*/false));
  }
  ad::set_num_threads(previous);
  for (const PredictedPaths& p : by_threads) {
    ASSERT_EQ(p.paths.size(), stretches.size());
    EXPECT_EQ(p.failed(), 1);
    EXPECT_FALSE(p.failures[1].empty());  // q0 = 2 blows up at t = 0.5
    EXPECT_TRUE(p.paths[1].array().isNaN().all());
    for (std::size_t i : {0u, 2u, 3u, 4u}) {
      EXPECT_TRUE(p.failures[i].empty()) << p.failures[i];
      const double q0 = stretches[i].x(0, 0);
      for (Eigen::Index k = 0; k < 11; ++k) {
        const double t = stretches[i].t(k);
        EXPECT_NEAR(p.paths[i](k, 0), q0 / (1 - q0 * t), 1e-7 * (1 + std::abs(q0)));
      }
    }
  }
  for (std::size_t i : {0u, 2u, 3u, 4u}) EXPECT_EQ(by_threads[0].paths[i], by_threads[1].paths[i]);
}

// Batched, a blow-up fails the batch, which then goes one stretch at a time: the others keep
// their paths.
TEST(PredictPaths, ABatchThatFailsFallsBackToOneAtATime) {
  const std::vector<Stretch> stretches = stretches_from({-1.0, 2.0, 0.25});
  const PredictedPaths p = predict_paths(stretches, dopri5_predictor(kExplosive));
  ASSERT_EQ(p.paths.size(), 3u);
  EXPECT_EQ(p.failed(), 1);
  EXPECT_FALSE(p.failures[1].empty());
  EXPECT_NEAR(p.paths[2](10, 0), 0.25 / (1 - 0.25), 1e-7);
  EXPECT_NEAR(p.paths[0](10, 0), -1.0 / 2.0, 1e-7);
}

}  // namespace
}  // namespace hnn::tasks
