#pragma once
// --swim-scale auto (docs/sampled.md, "The SWIM scale"): how steep a SWIM neuron is between its
// two data points, chosen by validation. The peer's scale (atanh(1/2)) suits none of its three
// protocols best: Henon-Heiles, a cubic, wants neurons 8-30 times smoother (their near-linear
// stretches combine into polynomials), the double pendulum about twice as steep. The walk starts
// at the peer's scale and halves it while the held-out error falls, or else doubles it, so a fit
// costs three to six fits of the validation fold rather than one per scale of a grid.

#include <functional>
#include <vector>

#include "nn/sampled/sampled_fit.h"

namespace hnn::nn::sampled {

/// The scales the walk may reach: kPeerSwimScale * 2^k, k = -5 ... 2, smallest first.
std::vector<double> swim_scale_ladder();

/// A scale replaces the best so far only when its held-out error is this many times smaller. On
/// noisy targets the scales' errors differ by a few percent, which says nothing (the spring's
/// 0.268 at the peer's scale, 0.260 at an eighth of it; the two-body baseline's 27% lower error
/// at half the scale came with a higher test loss and 85x slower rollouts); on exact ones a
/// halving gains 4-100x (docs/sampled.md, "The SWIM scale").
inline constexpr double kScaleGain = 1.5;

/// Walks swim_scale_ladder() from kPeerSwimScale: down while each scale's held-out error
/// (`error_at`) is kScaleGain times below the best so far, then, if the first step down was not,
/// up the same way. `keep_last` is called when the scale just scored becomes the best (the first
/// always does). Returns the best scale and every scale tried, in order, in `curve`.
double walk_scales(const std::function<double(double)>& error_at,
                   const std::function<void()>& keep_last, std::vector<ScaleTrial>& curve);

}  // namespace hnn::nn::sampled
