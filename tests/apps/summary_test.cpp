// What `hnn train` and `hnn evaluate` print (apps/hnn/commands/summary.cpp), from metrics.json's
// keys alone. The valid prediction time: a rollout whose error never passed the threshold counts
// its whole span, so when every one did the time is the rollouts' length and says so. R² near 1:
// its distance from 1, which four digits would round away.

#include "apps/hnn/commands/summary.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace {

nlohmann::json rollouts(int censored, int floor_censored) {
  return {{"valid_prediction_time", censored == 100 ? 1.98 : 1.63},
          {"valid_prediction_time_se", censored == 100 ? 2.9e-16 : 0.058},
          {"valid_prediction_time_count", 100},
          {"valid_prediction_censored", censored},
          {"valid_prediction_threshold", 0.1},
          {"valid_prediction_time_floor", 20.0},
          {"valid_prediction_floor_censored", floor_censored}};
}

std::string rollout_line(const nlohmann::json& m) {
  const std::string text = hnn::app::metrics_summary(m);
  const auto start = text.find("  rollouts   valid prediction time");
  return start == std::string::npos ? "" : text.substr(start, text.find('\n', start) - start);
}

TEST(Summary, AValidTimeWhereEveryRolloutStayedBelowTheThresholdSaysSoWithoutASpread) {
  EXPECT_EQ(rollout_line(rollouts(100, 0)),
            "  rollouts   valid prediction time: the whole rollout (1.98); the relative state "
            "error of all 100 stayed below 0.1; the truth perturbed by 1e-4: 20");
}

TEST(Summary, AValidTimeWithSomeRolloutsToTheEndIsALowerBound) {
  EXPECT_EQ(rollout_line(rollouts(3, 100)),
            "  rollouts   valid prediction time 1.63 ± 0.058 (until the relative state error "
            "passes 0.1); 3 of 100 rollouts never passed it and count their whole span, so it is "
            "a lower bound; the truth perturbed by 1e-4: the whole rollout, 20");
}

TEST(Summary, AValidTimeOfRolloutsThatAllPassedTheThresholdIsAMeanWithItsError) {
  EXPECT_EQ(rollout_line(rollouts(0, 0)),
            "  rollouts   valid prediction time 1.63 ± 0.058 (until the relative state error "
            "passes 0.1); the truth perturbed by 1e-4: 20");
}

TEST(Summary, AnRSquaredThatFourDigitsWouldRoundToOneGivesItsDistanceFromOne) {
  const std::string text = hnn::app::metrics_summary(
      {{"test_loss", 2.63e-5}, {"train_loss", 3e-5}, {"test_r2", 0.999974}, {"train_r2", 0.9987}});
  EXPECT_NE(text.find("; R² test 1 - 2.6e-05, train 0.9987\n"), std::string::npos) << text;
  EXPECT_NE(hnn::app::metrics_summary({{"test_loss", 1.0}, {"test_r2", 1.0}}).find("R² test 1\n"),
            std::string::npos);
}

}  // namespace
