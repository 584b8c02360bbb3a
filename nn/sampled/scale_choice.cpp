#include "nn/sampled/scale_choice.h"

#include <cmath>
#include <cstddef>

namespace hnn::nn::sampled {

namespace {
constexpr int kLowestPower = -5, kHighestPower = 2;
}

std::vector<double> swim_scale_ladder() {
  std::vector<double> ladder;
  for (int k = kLowestPower; k <= kHighestPower; ++k)
    ladder.push_back(std::ldexp(kPeerSwimScale, k));
  return ladder;
}

double walk_scales(const std::function<double(double)>& error_at,
                   const std::function<void()>& keep_last, std::vector<ScaleTrial>& curve) {
  const std::vector<double> ladder = swim_scale_ladder();
  const auto peer = std::size_t(-kLowestPower);
  curve.clear();
  std::size_t best = peer;
  double best_error = error_at(ladder[peer]);
  keep_last();
  curve.push_back({ladder[peer], best_error});
  // One direction: step while the error falls kScaleGain-fold.
  const auto walk = [&](int step) {
    for (auto i = std::ptrdiff_t(peer) + step; i >= 0 && i < std::ptrdiff_t(ladder.size());
         i += step) {
      const double error = error_at(ladder[std::size_t(i)]);
      curve.push_back({ladder[std::size_t(i)], error});
      if (!(error * kScaleGain < best_error)) break;
      keep_last();
      best = std::size_t(i);
      best_error = error;
    }
  };
  walk(-1);
  if (best == peer) walk(+1);  // the first halving did not gain enough
  return ladder[best];
}

}  // namespace hnn::nn::sampled
