// --swim-scale (nn/sampled/scale_choice.h): how steep a SWIM neuron is between its two data
// points, given or chosen by validation.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "nn/hnn.h"
#include "nn/sampled/sampled_fit.h"
#include "nn/sampled/scale_choice.h"

namespace hnn::nn {
namespace swim_scale_test {  // a name of its own: the unity build joins the test files

using sampled::swim_scale_ladder;
using sampled::walk_scales;

// The ladder's power of two of a scale: scale = kPeerSwimScale * 2^k.
int power_of(double scale) { return int(std::lround(std::log2(scale / kPeerSwimScale))); }

std::vector<int> powers_tried(const std::vector<ScaleTrial>& curve) {
  std::vector<int> out;
  for (const ScaleTrial& t : curve) out.push_back(power_of(t.scale));
  return out;
}

TEST(SwimScale, LadderIsThePeersScaleTimesPowersOfTwo) {
  const std::vector<double> ladder = swim_scale_ladder();
  ASSERT_EQ(ladder.size(), 8u);
  EXPECT_DOUBLE_EQ(ladder.front(), kPeerSwimScale / 32);
  EXPECT_DOUBLE_EQ(ladder.back(), kPeerSwimScale * 4);
  EXPECT_NE(std::ranges::find(ladder, kPeerSwimScale), ladder.end());
}

// Down from the peer's scale while the error falls by kScaleGain a step, one step past the best;
// up instead when the first step down does not; differences within kScaleGain (a noisy target's)
// leave the peer's scale; a NaN error stops the walk like a worse one. keep_last is called for
// each new best, so the last one kept is the scale returned.
TEST(SwimScale, WalkGoesDownhillFromThePeersScaleWhileItGainsClearly) {
  std::vector<ScaleTrial> curve;
  double last = 0, kept = 0;
  const auto walk = [&](const std::function<double(double)>& error) {
    const double chosen = walk_scales(
        [&](double scale) {
          last = scale;
          return error(scale);
        },
        [&] { kept = last; }, curve);
    EXPECT_EQ(kept, chosen);
    return power_of(chosen);
  };
  const auto bowl = [](int best, double base) {
    return [=](double scale) { return std::pow(base, std::abs(power_of(scale) - best)); };
  };
  EXPECT_EQ(walk(bowl(-3, 10)), -3);
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, -2, -3, -4}));
  EXPECT_EQ(walk(bowl(1, 10)), 1);
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, 1, 2}));
  EXPECT_EQ(walk(bowl(-9, 10)), -5);  // the ladder's end
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, -2, -3, -4, -5}));
  EXPECT_EQ(walk(bowl(0, 10)), 0);
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, 1}));
  EXPECT_EQ(walk(bowl(-3, 1.2)), 0);  // 20% a step: within the noise of a held-out error
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, 1}));
  const auto nan_below = [](double scale) {
    const int k = power_of(scale);
    return k < 0 ? std::numeric_limits<double>::quiet_NaN() : std::pow(10.0, -k);
  };
  EXPECT_EQ(walk(nan_below), 2);
  EXPECT_EQ(powers_tried(curve), (std::vector<int>{0, -1, 1, 2}));
}

// How many of a fitted one-layer MLP's neurons have tanh input -scale at one data point and
// +scale at another.
int neurons_on_pairs(const DynamicsModel<double>& model, const Matrix<double>& x, double scale) {
  const Linear<double>& layer = model.mlp().layers()[0];
  const Matrix<double> z = (x * layer.weight().value()).rowwise() + layer.bias().value().row(0);
  int on_pairs = 0;
  for (Index j = 0; j < z.cols(); ++j) {
    const double low = (z.col(j).array() + scale).abs().minCoeff();
    const double high = (z.col(j).array() - scale).abs().minCoeff();
    on_pairs += low < 1e-9 && high < 1e-9;
  }
  return on_pairs;
}

struct Problem {
  Matrix<double> x, dxdt;
};

// Henon-Heiles (alpha = 1) in [-2, 2]^4 with its exact field: a cubic H.
Problem henon_heiles(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2);
  Problem out{Matrix<double>(n, 4), Matrix<double>(n, 4)};
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 4; ++k) out.x(i, k) = u(rng);
    const double q1 = out.x(i, 0), q2 = out.x(i, 1);
    out.dxdt.row(i) << out.x(i, 2), out.x(i, 3), -(q1 + 2 * q1 * q2), -(q2 + q1 * q1 - q2 * q2);
  }
  return out;
}

double field_error(const DynamicsModel<double>& model, const Problem& test) {
  return (model.field(test.x) - test.dxdt).norm() / test.dxdt.norm();
}

// A SWIM neuron is built on a pair of data points: its tanh input is -s at one and +s at the
// other (the peer's s = atanh(1/2), or the one given); ELM's are not.
TEST(SwimScale, SwimNeuronsSitOnPairsOfDataPoints) {
  const Problem train = henon_heiles(300, 2);
  EXPECT_DOUBLE_EQ(kPeerSwimScale, std::atanh(0.5));
  DynamicsConfig c;
  c.dim = 4;
  c.hidden = {50};
  for (HiddenSampler sampler :
       {HiddenSampler::kUswim, HiddenSampler::kAswim, HiddenSampler::kElm}) {
    for (double scale : {kPeerSwimScale, 0.1}) {
      std::mt19937_64 rng(1);
      auto model = make_model<double>(c, rng);
      fit_sampled(*model, train.x, train.dxdt, {.sampler = sampler, .swim_scale = scale});
      EXPECT_EQ(neurons_on_pairs(*model, train.x, scale), sampler == HiddenSampler::kElm ? 0 : 50)
          << name_of(kHiddenSamplerNames, sampler) << " at scale " << scale;
    }
  }
}

// --swim-scale auto walks from the peer's scale and keeps the one whose held-out field error is
// smallest; the neurons sit at that scale, and on a cubic H the field is far better than at the
// peer's (the peer's Henon-Heiles protocol goes from 7e-8 to 2e-10 in docs/sampled.md). ELM reads
// no scale.
TEST(SwimScale, AutoKeepsTheScaleOfTheSmallestHeldOutError) {
  const Problem train = henon_heiles(2000, 4), test = henon_heiles(500, 5);
  DynamicsConfig c;
  c.dim = 4;
  c.hidden = {200};
  std::mt19937_64 rng(1);
  auto peer = make_model<double>(c, rng), chosen = make_model<double>(c, rng);
  fit_sampled(*peer, train.x, train.dxdt, {.swim_scale = kPeerSwimScale, .rcond = 1e-13});
  const SampledFitReport r = fit_sampled(*chosen, train.x, train.dxdt, {.rcond = 1e-13});
  ASSERT_GE(r.scale_validation.size(), 2u);
  EXPECT_EQ(r.scale_validation.front().scale, kPeerSwimScale);
  const auto best = std::ranges::min_element(r.scale_validation, {}, &ScaleTrial::error);
  EXPECT_EQ(r.swim_scale, best->scale);
  EXPECT_LT(r.swim_scale, kPeerSwimScale);
  EXPECT_EQ(neurons_on_pairs(*chosen, train.x, r.swim_scale), 200);
  EXPECT_LT(field_error(*chosen, test), 0.1 * field_error(*peer, test));
  const SampledFitReport elm =
      fit_sampled(*chosen, train.x, train.dxdt, {.sampler = HiddenSampler::kElm});
  EXPECT_TRUE(elm.scale_validation.empty());
  EXPECT_EQ(elm.swim_scale, 0);
}

}  // namespace swim_scale_test
}  // namespace hnn::nn
