#include "tasks/evaluate/run_warnings.h"

#include <fmt/format.h>

#include <cmath>

namespace hnn::tasks {

using json = nlohmann::json;

namespace {

// A point's test loss, or its train loss where there is no test split.
double curve_loss(const CurvePoint& p) {
  return std::isnan(p.test_loss) ? p.train_loss : p.test_loss;
}

}  // namespace

std::vector<std::string> run_warnings(const std::vector<CurvePoint>& curve, const json& metrics) {
  std::vector<std::string> warnings;
  if (curve.size() >= 2) {
    const CurvePoint &first = curve.front(), &last = curve.back();
    const std::string which = std::isnan(first.test_loss) ? "training" : "test";
    if (!(curve_loss(last) < curve_loss(first))) {
      warnings.push_back(fmt::format(
          "the {} loss did not fall: {:.3g} at step {}, {:.3g} at the last step ({}); the run "
          "ended no better than it started (a smaller --lr may help)",
          which, curve_loss(first), first.step, curve_loss(last), last.step));
    }
  }
  const auto truth = metrics.find("truth_rollout_loss");
  if (!curve.empty() && truth != metrics.end() && truth->is_number() &&
      truth->get<double>() > kTruthLossRatio * curve.back().train_loss) {
    warnings.push_back(fmt::format(
        "the true system's own rollout loss through the training's integrator is {:.3g}, over "
        "{:g} times the training's last loss ({:.3g}): at this step the integrator cannot follow "
        "the true motion on some training windows, and the model learned a motion it can follow; "
        "a smaller --dt helps",
        truth->get<double>(), kTruthLossRatio, curve.back().train_loss));
  }
  const auto r2 = metrics.find("test_r2");
  if (r2 != metrics.end() && r2->is_number() && r2->get<double>() < kLowR2) {
    warnings.push_back(fmt::format(
        "the test R^2 is {:.3g}, below {}: the model explains almost none of the spread of the "
        "test dx/dt",
        r2->get<double>(), kLowR2));
  }
  return warnings;
}

}  // namespace hnn::tasks
